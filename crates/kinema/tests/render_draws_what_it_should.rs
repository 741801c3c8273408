//! The renderer draws what it should: discs where they are with antialiased edges, nearer
//! spheres over farther ones, perspective sizes, nothing behind the eye, and the same bytes
//! for every thread count; with scenery, floors below the horizon, sphere obstacles in depth
//! order with the particles, box outlines on their edges only, and named errors; springs as
//! lines from rim to rim, in depth order in 3D; cameras that fit a box into both fields of view;
//! mesh colliders translucent, outlined on their creases, and ordered by depth; moving
//! colliders drawn where their poses put them.

// The tests sit in a module named `render` so that `cargo test render` selects them.
mod render {
    use kinema::collide::{BoxContainer, Collider, Plane, SphereObstacle, Surface, TriangleMesh};
    use kinema::render::mesh_paint::MESH_ALPHA;
    use kinema::render::paint::{BOX_FLOOR_COLOR, FLOOR_COLOR, LINE_COLOR, OBSTACLE_COLOR};
    use kinema::render::{
        collider_boxes, render, render_frame, render_scene, scene_extent, text, Camera, Frame, RenderParams, RenderStats,
        Scenery, FRAME_MARGIN,
    };
    use kinema::Error;

    const BG: [u8; 3] = [255, 255, 255];

    fn frame(
        camera: &Camera,
        pos: &[[f64; 3]],
        radius: &[f64],
        colors: &[[u8; 3]],
        w: usize,
        h: usize,
    ) -> (Vec<u8>, RenderStats) {
        let mut image = vec![0u8; w * h * 3];
        let positions: Vec<f64> = pos.iter().flatten().copied().collect();
        let colors: Vec<u8> = colors.iter().flatten().copied().collect();
        let stats = render(camera, &positions, radius, &colors, &RenderParams::new(w, h), &mut image).unwrap();
        (image, stats)
    }

    fn pixel(image: &[u8], w: usize, i: usize, j: usize) -> [u8; 3] {
        let o = 3 * (j * w + i);
        [image[o], image[o + 1], image[o + 2]]
    }

    /// Width in pixels of the non-background run through the middle of row `j`.
    fn run_width(image: &[u8], w: usize, j: usize) -> usize {
        (0..w).filter(|&i| pixel(image, w, i, j) != BG).count()
    }

    #[test]
    fn disc_is_full_at_its_centre_background_far_away_and_blended_at_its_edge() {
        // [0, 10]² onto 100 × 100: 10 px per metre, world (x, y) → pixel (10x, 100 − 10y).
        let cam = Camera::fit_2d([0.0, 0.0], [10.0, 10.0], 100, 100).unwrap();
        // Centre at pixel coordinates (50.5, 49.5) = the centre of pixel (50, 49); radius 20 px.
        let (img, stats) = frame(&cam, &[[5.05, 5.05, 0.0]], &[2.0], &[[200, 0, 0]], 100, 100);
        assert_eq!(stats, RenderStats { drawn: 1, culled: 0 });
        assert_eq!(pixel(&img, 100, 50, 49), [200, 0, 0]);
        assert_eq!(pixel(&img, 100, 60, 55), [200, 0, 0]);
        assert_eq!(pixel(&img, 100, 5, 5), BG);
        assert_eq!(pixel(&img, 100, 95, 95), BG);
        // Pixel (70, 49) has its centre exactly on the edge (20 px right): half covered.
        let edge = pixel(&img, 100, 70, 49);
        assert!(
            (225..=230).contains(&edge[0]) && (125..=130).contains(&edge[1]),
            "edge pixel {edge:?}"
        );
        // One pixel further out is untouched, one further in is full.
        assert_eq!(pixel(&img, 100, 71, 49), BG);
        assert_eq!(pixel(&img, 100, 69, 49), [200, 0, 0]);
        // The outline is round: the run through the centre row is the diameter, 40 px ± 1.
        assert!((39..=41).contains(&run_width(&img, 100, 49)));
    }

    #[test]
    fn nearer_sphere_covers_a_farther_one_whatever_the_input_order() {
        let cam = Camera::perspective([0.0, -10.0, 0.0], [0.0; 3], [0.0, 0.0, 1.0], 40.0).unwrap();
        let far = [0.0, 0.0, 0.0];
        let near = [0.0, -5.0, 0.0];
        for (pos, colors) in [
            ([far, near], [[255, 0, 0], [0, 255, 0]]),
            ([near, far], [[0, 255, 0], [255, 0, 0]]),
        ] {
            let radius = if pos[0] == far { [1.0, 0.3] } else { [0.3, 1.0] };
            let (img, stats) = frame(&cam, &pos, &radius, &colors, 200, 200);
            assert_eq!(stats.drawn, 2);
            let c = pixel(&img, 200, 100, 100);
            // The white highlight adds a little of every channel; the hue is what tells them apart.
            assert!(c[1] > c[0] + 100, "centre shows the near green sphere: {c:?}");
            // Outside the near sphere but inside the far one: red.
            let side = pixel(&img, 200, 100 + 20, 100);
            assert!(
                side[0] > side[1] + 50 && side[2] < 10,
                "the far red sphere around it: {side:?}"
            );
        }
    }

    #[test]
    fn a_sphere_twice_as_far_is_half_as_big() {
        let (w, h) = (400, 400);
        let cam = Camera::perspective([0.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0], 60.0).unwrap();
        // Focal length f = (H/2) / tan(30°) px; a sphere of radius R at distance D spans f·R/D px.
        let f = 200.0 / 30f64.to_radians().tan();
        let mut diameters = vec![];
        for d in [10.0, 20.0] {
            let (img, _) = frame(&cam, &[[0.0, d, 0.0]], &[0.5], &[[0, 0, 255]], w, h);
            let measured = run_width(&img, w, 200) as f64;
            assert!((measured - 2.0 * f * 0.5 / d).abs() <= 2.0, "distance {d}: {measured} px");
            diameters.push(measured);
        }
        // Radii within 1 px of half.
        assert!((diameters[0] / 2.0 - diameters[1]).abs() <= 2.0, "{diameters:?}");
    }

    #[test]
    fn particles_behind_the_camera_are_skipped_and_tiny_ones_stay_visible() {
        let cam = Camera::perspective([0.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0], 60.0).unwrap();
        let (img, stats) = frame(&cam, &[[0.0, -3.0, 0.0]], &[1.0], &[[0, 0, 0]], 64, 64);
        assert_eq!(stats, RenderStats { drawn: 0, culled: 1 });
        assert!(img.iter().all(|&b| b == 255));
        // 1 mm at 1 km would be 5e-5 px: drawn at the 1 px minimum radius instead.
        let (img, stats) = frame(&cam, &[[0.0, 1000.0, 0.0]], &[1e-3], &[[0, 0, 0]], 64, 64);
        assert_eq!(stats.drawn, 1);
        assert!(pixel(&img, 64, 32, 32)[0] < 128, "{:?}", pixel(&img, 64, 32, 32));
    }

    /// A few thousand spheres from a fixed linear congruential sequence.
    fn cloud(n: usize) -> (Vec<f64>, Vec<f64>, Vec<u8>) {
        let mut s: u64 = 12345;
        let mut next = || {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64
        };
        let positions = (0..3 * n).map(|_| next()).collect();
        let radius = (0..n).map(|_| 0.005 + 0.02 * next()).collect();
        let colors = (0..3 * n).map(|_| (255.0 * next()) as u8).collect();
        (positions, radius, colors)
    }

    #[test]
    fn frames_are_identical_for_one_and_two_threads() {
        let (positions, radius, colors) = cloud(3000);
        // Springs between particles far apart and near: lines across many bands, and short ones.
        let springs: Vec<[usize; 2]> = (0..600).map(|k| [k, (k * 7 + 1) % 3000]).collect();
        let (w, h) = (320, 200);
        let params = RenderParams::new(w, h);
        let cams = [
            Camera::frame_box([0.0; 3], [1.0; 3], [1.0, -1.5, 0.8], 40.0, w, h).unwrap(),
            Camera::fit_2d([0.0, 0.0], [1.0, 1.0], w, h).unwrap(),
        ];
        // Without scenery, and with a floor, an open box (no lid), a slanted wall and an
        // obstacle in the middle of the cloud.
        let sceneries = [
            Scenery::default(),
            Scenery {
                colliders: vec![
                    plane([0.0; 3], [0.0, 0.0, 1.0]),
                    plane([0.0; 3], [1.0, 0.3, 0.2]),
                    cuboid([0.0; 3], [1.0, 1.0, f64::INFINITY]),
                    obstacle([0.5; 3], 0.2),
                ],
                extent: None,
            },
        ];
        for cam in cams {
            for scenery in &sceneries {
                let images: Vec<Vec<u8>> = [1, 2, 3]
                    .iter()
                    .map(|&threads| {
                        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
                        let mut image = vec![0u8; w * h * 3];
                        let frame = Frame {
                            springs: &springs,
                            scenery,
                            ..Frame::particles(&positions, &radius, &colors)
                        };
                        pool.install(|| render_frame(&cam, &frame, &params, &mut image)).unwrap();
                        image
                    })
                    .collect();
                assert!(images[0].iter().any(|&b| b != 255));
                assert_eq!(
                    images[0],
                    images[1],
                    "1 vs 2 threads, {cam:?}, {} items",
                    scenery.colliders.len()
                );
                assert_eq!(
                    images[0],
                    images[2],
                    "1 vs 3 threads, {cam:?}, {} items",
                    scenery.colliders.len()
                );
            }
        }
    }

    #[test]
    fn bad_input_names_the_parameter() {
        let cam = Camera::fit_2d([0.0, 0.0], [1.0, 1.0], 10, 10).unwrap();
        let mut image = vec![0u8; 300];
        let p = RenderParams::new(10, 10);
        let name = |e: Error| match e {
            Error::InvalidParameter { parameter, .. } => parameter,
            other => panic!("{other}"),
        };
        assert_eq!(
            name(render(&cam, &[0.0; 5], &[1.0, 1.0], &[0; 6], &p, &mut image).unwrap_err()),
            "positions"
        );
        assert_eq!(
            name(render(&cam, &[0.0; 3], &[1.0], &[0; 2], &p, &mut image).unwrap_err()),
            "colors"
        );
        assert_eq!(
            name(render(&cam, &[f64::NAN, 0.0, 0.0], &[1.0], &[0; 3], &p, &mut image).unwrap_err()),
            "positions[0]"
        );
        assert_eq!(
            name(render(&cam, &[0.0; 3], &[-1.0], &[0; 3], &p, &mut image).unwrap_err()),
            "radius[0]"
        );
        assert_eq!(
            name(render(&cam, &[0.0; 3], &[1.0], &[0; 3], &p, &mut image[..299]).unwrap_err()),
            "image"
        );
        assert_eq!(
            name(Camera::perspective([0.0; 3], [0.0; 3], [0.0, 0.0, 1.0], 40.0).unwrap_err()),
            "target"
        );
        assert_eq!(
            name(Camera::perspective([0.0; 3], [0.0, 0.0, 1.0], [0.0, 0.0, 1.0], 40.0).unwrap_err()),
            "up"
        );
        assert_eq!(
            name(Camera::perspective([0.0; 3], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0], 180.0).unwrap_err()),
            "fov_y_deg"
        );
        assert_eq!(
            name(text::draw_text(&mut image, 10, 10, [0, 0], 1, [0; 3], "t = x").unwrap_err()),
            "text"
        );
    }

    #[test]
    fn time_stamp_text_differs_between_times() {
        let (w, h) = (80, 20);
        let mut a = vec![255u8; w * h * 3];
        let mut b = a.clone();
        let drawn = text::draw_text(&mut a, w, h, [2, 2], 2, [0; 3], "t = 1.25 s").unwrap();
        text::draw_text(&mut b, w, h, [2, 2], 2, [0; 3], "t = 1.50 s").unwrap();
        assert_eq!(drawn, 10 * 6 * 2);
        assert_ne!(a, b);
        assert!(a.contains(&0));
    }

    // -- scenery ------------------------------------------------------------------------------

    fn scene_frame(
        camera: &Camera,
        pos: &[[f64; 3]],
        radius: &[f64],
        colors: &[[u8; 3]],
        scenery: &Scenery,
        w: usize,
        h: usize,
    ) -> Vec<u8> {
        let mut image = vec![0u8; w * h * 3];
        let positions: Vec<f64> = pos.iter().flatten().copied().collect();
        let colors: Vec<u8> = colors.iter().flatten().copied().collect();
        render_scene(
            camera,
            &positions,
            radius,
            &colors,
            scenery,
            &RenderParams::new(w, h),
            &mut image,
        )
        .unwrap();
        image
    }

    fn items(colliders: Vec<Collider>) -> Scenery {
        Scenery { colliders, extent: None }
    }

    fn plane(point: [f64; 3], normal: [f64; 3]) -> Collider {
        Plane::new(point, normal, Surface::default()).unwrap().into()
    }

    fn cuboid(lo: [f64; 3], hi: [f64; 3]) -> Collider {
        BoxContainer::new(lo, hi, Surface::default()).unwrap().into()
    }

    fn obstacle(center: [f64; 3], radius: f64) -> Collider {
        SphereObstacle::new(center, radius, Surface::default()).unwrap().into()
    }

    /// A neutral grey: the three channels within `tol` of each other and darker than white.
    fn is_grey(c: [u8; 3], tol: u8) -> bool {
        let (lo, hi) = (c.iter().min().unwrap(), c.iter().max().unwrap());
        hi - lo <= tol && *hi < 250
    }

    #[test]
    fn a_floor_colours_the_ground_below_the_horizon_and_not_the_sky() {
        // The eye 1 m above the floor z = 0, looking horizontally along +y: the horizon is
        // the middle row; the floor patch (which reaches behind the camera and is cut at the
        // near distance) fills the lower half, the sky stays the background.
        let (w, h) = (160, 120);
        let cam = Camera::perspective([0.0, 0.0, 1.0], [0.0, 10.0, 1.0], [0.0, 0.0, 1.0], 60.0).unwrap();
        let floor = items(vec![plane([0.0; 3], [0.0, 0.0, 1.0])]);
        let img = scene_frame(&cam, &[], &[], &[], &floor, w, h);
        for j in 0..55 {
            assert!((0..w).all(|i| pixel(&img, w, i, j) == BG), "sky row {j} is background");
        }
        for j in 65..h {
            let floor_pixels = (0..w).filter(|&i| is_grey(pixel(&img, w, i, j), 6)).count();
            assert_eq!(floor_pixels, w, "ground row {j} is floor everywhere");
        }
        // Most of the ground is the plain floor colour (the faint grid covers a few pixels).
        let plain = (65..h)
            .flat_map(|j| (0..w).map(move |i| (i, j)))
            .filter(|&(i, j)| {
                let c = pixel(&img, w, i, j);
                (0..3).all(|k| c[k].abs_diff(FLOOR_COLOR[k]) <= 3)
            })
            .count();
        assert!(plain > (h - 65) * w / 2, "{plain} plain floor pixels");
        // Seen from below, the same floor is overhead: the upper half.
        let below = Camera::perspective([0.0, 0.0, -1.0], [0.0, 10.0, -1.0], [0.0, 0.0, 1.0], 60.0).unwrap();
        let img = scene_frame(&below, &[], &[], &[], &floor, w, h);
        assert!(is_grey(pixel(&img, w, 80, 5), 6) && pixel(&img, w, 80, 115) == BG);
        // Looking up and away, the floor is entirely behind the view: nothing is drawn, and
        // the parts behind the eye do not wrap around into the image.
        let up = Camera::perspective([0.0, 0.0, 1.0], [0.0, 5.0, 4.0], [0.0, 0.0, 1.0], 40.0).unwrap();
        let img = scene_frame(&up, &[], &[], &[], &floor, w, h);
        assert!(img.iter().all(|&b| b == 255));
    }

    #[test]
    fn a_floor_is_drawn_under_the_particles() {
        let (w, h) = (160, 120);
        let cam = Camera::perspective([0.0, -4.0, 2.0], [0.0, 0.0, 0.0], [0.0, 0.0, 1.0], 40.0).unwrap();
        let floor = items(vec![plane([0.0, 0.0, -0.3], [0.0, 0.0, 1.0])]);
        // A red ball resting on the floor at the image centre: its pixels are red (shaded),
        // the floor's grey around it.
        let img = scene_frame(&cam, &[[0.0; 3]], &[0.3], &[[255, 0, 0]], &floor, w, h);
        for (i, j) in [(80, 60), (80, 52), (74, 64)] {
            let c = pixel(&img, w, i, j);
            assert!(
                c[0] > 60 && c[1] < c[0] / 3 && c[2] < c[0] / 3,
                "ball pixel ({i}, {j}): {c:?}"
            );
        }
        assert!(is_grey(pixel(&img, w, 80, 100), 6), "floor below the ball");
    }

    fn luma(c: [u8; 3]) -> f64 {
        0.299 * c[0] as f64 + 0.587 * c[1] as f64 + 0.114 * c[2] as f64
    }

    /// The darkest luma and the count of the pixels darker than the bare floor by more than 4
    /// (the shadow's), outside the ball's own pixels (those the ball covers with no scenery,
    /// grown by 2 px).
    fn shadow_of(cam: &Camera, centre: [f64; 3], r: f64, scenery: &Scenery, w: usize, h: usize) -> (f64, usize) {
        let red = [[200, 30, 30]];
        let ball = scene_frame(cam, &[centre], &[r], &red, &items(vec![]), w, h);
        let bare = scene_frame(cam, &[], &[], &[], scenery, w, h);
        let img = scene_frame(cam, &[centre], &[r], &red, scenery, w, h);
        let near_ball = |i: usize, j: usize| {
            (i.saturating_sub(2)..(i + 3).min(w))
                .any(|x| (j.saturating_sub(2)..(j + 3).min(h)).any(|y| pixel(&ball, w, x, y) != BG))
        };
        let (mut darkest, mut count) = (255.0f64, 0);
        for j in 0..h {
            for i in 0..w {
                if near_ball(i, j) {
                    continue;
                }
                let (l, l0) = (luma(pixel(&img, w, i, j)), luma(pixel(&bare, w, i, j)));
                if l < l0 - 4.0 {
                    darkest = darkest.min(l);
                    count += 1;
                }
            }
        }
        (darkest, count)
    }

    #[test]
    fn a_ball_casts_a_contact_shadow_that_fades_with_its_height() {
        let (w, h) = (200, 150);
        let cam = Camera::perspective([0.0, -4.0, 4.0], [0.0, 0.0, 0.3], [0.0, 0.0, 1.0], 40.0).unwrap();
        let floor = items(vec![plane([0.0; 3], [0.0, 0.0, 1.0])]);
        let r = 0.3;
        // Resting on the floor: a dark patch around where it touches.
        let (rest_dark, rest_n) = shadow_of(&cam, [0.0, 0.0, r], r, &floor, w, h);
        // 1 m up: the patch straight below is much fainter and wider.
        let (up_dark, up_n) = shadow_of(&cam, [0.0, 0.0, r + 1.0], r, &floor, w, h);
        let floor_luma = luma(pixel(&scene_frame(&cam, &[], &[], &[], &floor, w, h), w, 100, 75));
        eprintln!("floor {floor_luma:.1}; resting: darkest {rest_dark:.1}, {rest_n} px; 1 m up: darkest {up_dark:.1}, {up_n} px");
        assert!(
            rest_dark < floor_luma - 40.0,
            "resting shadow {rest_dark} on floor {floor_luma}"
        );
        assert!(up_dark > rest_dark + 20.0 && up_dark < floor_luma - 5.0, "1 m up: {up_dark}");
        assert!(up_n > rest_n, "the high ball's shadow is wider: {up_n} vs {rest_n} px");
        // A box's floor takes shadows too; with no floor there is none.
        let boxed = items(vec![cuboid([-2.0, -2.0, 0.0], [2.0, 2.0, 3.0])]);
        let (box_dark, _) = shadow_of(&cam, [0.0, 0.0, r], r, &boxed, w, h);
        assert!(box_dark < luma(BOX_FLOOR_COLOR) - 40.0, "box floor shadow {box_dark}");
        let (none_dark, none_n) = shadow_of(&cam, [0.0, 0.0, r], r, &items(vec![]), w, h);
        assert_eq!((none_dark, none_n), (255.0, 0), "no floor, no shadow");
    }

    #[test]
    fn planes_are_translucent_and_cut_where_they_meet() {
        let (w, h) = (200, 150);
        let cam = Camera::perspective([0.0, -10.0, 0.0], [0.0; 3], [0.0, 0.0, 1.0], 40.0).unwrap();
        // A plane tilted towards the camera, and a red ball behind it (seen through it).
        let tilted = items(vec![plane([0.0, 0.0, 0.0], [0.0, -1.0, 1.0])]);
        let red = [[220, 20, 20]];
        let plane_only = pixel(&scene_frame(&cam, &[], &[], &[], &tilted, w, h), w, 100, 75);
        let with_ball = pixel(
            &scene_frame(&cam, &[[0.0, 2.0, 0.0]], &[0.4], &red, &tilted, w, h),
            w,
            100,
            75,
        );
        eprintln!("plane alone {plane_only:?}, ball behind it {with_ball:?}");
        assert!(is_grey(plane_only, 10), "the plane: {plane_only:?}");
        assert!(
            with_ball[0] > with_ball[1] + 60,
            "the ball shows through the plane: {with_ball:?}"
        );
        // Translucent: over a blue background the plane's pixels stay bluish.
        let mut params = RenderParams::new(w, h);
        params.background = [40, 60, 220];
        let mut img = vec![0u8; w * h * 3];
        render_scene(&cam, &[], &[], &[], &tilted, &params, &mut img).unwrap();
        let over_blue = pixel(&img, w, 60, 120);
        eprintln!("the plane over a blue background {over_blue:?}");
        assert!(
            over_blue[2] > over_blue[0] + 80,
            "the background shows through: {over_blue:?}"
        );
        // Two crossing planes (a V trough along the view, crease x = 0, z = −1): each drawn
        // only on the free side of the other, so every pixel below the horizon shows one
        // facet, not the two planes' whole squares over each other.
        let v = items(vec![
            plane([0.0, 0.0, -1.0], [-1.0, 0.0, 1.0]),
            plane([0.0, 0.0, -1.0], [1.0, 0.0, 1.0]),
        ]);
        let img = scene_frame(&cam, &[], &[], &[], &v, w, h);
        // Uncut, the two squares would overlap below the horizon: two layers of plane.
        let two = pixel(
            &scene_frame(
                &cam,
                &[],
                &[],
                &[],
                &items(vec![plane([0.0, 0.0, -1.0], [0.0, 0.0, 1.0]); 2]),
                w,
                h,
            ),
            w,
            60,
            140,
        );
        let mut one_layer = 0;
        for j in 80..h {
            for i in 0..w {
                let c = pixel(&img, w, i, j);
                one_layer += usize::from((0..3).all(|k| c[k].abs_diff(FLOOR_COLOR[k]) <= 3));
            }
        }
        let below = pixel(&img, w, 94, 145);
        eprintln!(
            "V: {one_layer} of {} px below row 80 one plane thick {below:?}; two layers {two:?}",
            (h - 80) * w
        );
        assert!(one_layer > (h - 80) * w * 8 / 10 && luma(two) < luma(FLOOR_COLOR) - 15.0);
    }

    #[test]
    fn a_sphere_obstacle_hides_a_particle_behind_it_and_not_one_in_front() {
        let (w, h) = (200, 200);
        let cam = Camera::perspective([0.0, -10.0, 0.0], [0.0; 3], [0.0, 0.0, 1.0], 40.0).unwrap();
        let ball = items(vec![obstacle([0.0; 3], 1.0)]);
        let red = [[255, 0, 0]];
        let behind = scene_frame(&cam, &[[0.0, 3.0, 0.0]], &[0.2], &red, &ball, w, h);
        let c = pixel(&behind, w, 100, 100);
        assert!(is_grey(c, 12), "the obstacle covers the particle behind it: {c:?}");
        let in_front = scene_frame(&cam, &[[0.0, -3.0, 0.0]], &[0.2], &red, &ball, w, h);
        let c = pixel(&in_front, w, 100, 100);
        assert!(c[0] > c[1] + 100, "the particle in front covers the obstacle: {c:?}");
        // Beside the particle, still the obstacle; the same for the 2D disc, under particles.
        assert!(is_grey(pixel(&in_front, w, 100 + 20, 100), 12));
        let flat = Camera::fit_2d([-2.0, -2.0], [2.0, 2.0], w, h).unwrap();
        let img = scene_frame(&flat, &[[0.0, 0.0, 0.0]], &[0.2], &red, &ball, w, h);
        assert_eq!(pixel(&img, w, 100, 100), [255, 0, 0]);
        assert_eq!(pixel(&img, w, 100 + 30, 100), OBSTACLE_COLOR);
        assert_eq!(pixel(&img, w, 100 + 60, 100), BG);
    }

    #[test]
    fn a_2d_box_outline_lights_its_edges_and_not_its_interior() {
        // [0, 10]² onto 100 × 100: the box [2, 8]² has its sides on pixel lines 20 and 80.
        let (w, h) = (100, 100);
        let cam = Camera::fit_2d([0.0, 0.0], [10.0, 10.0], w, h).unwrap();
        let b = items(vec![cuboid([2.0, 2.0, -1.0], [8.0, 8.0, 1.0])]);
        let img = scene_frame(&cam, &[], &[], &[], &b, w, h);
        // A 2 px line centred on x = 20: pixels 19 and 20 (centres 0.5 px away) are covered,
        // clamp(w/2 + ½ − d, 0, 1) = clamp(1 + ½ − ½) = 1; pixels 18 and 21 (1.5 px) are not.
        for j in [30, 50, 70] {
            for i in [19, 20, 79, 80] {
                assert_eq!(pixel(&img, w, i, j), LINE_COLOR, "side pixel ({i}, {j})");
                assert_eq!(pixel(&img, w, j, i), LINE_COLOR, "top/bottom pixel ({j}, {i})");
            }
            for i in [17, 22, 50, 77, 82] {
                assert_eq!(pixel(&img, w, i, j), BG, "off-edge pixel ({i}, {j})");
            }
        }
        let lit = img.chunks(3).filter(|p| p != &BG).count();
        assert!(
            (4 * 2 * 60..=4 * 2 * 64).contains(&lit),
            "{lit} pixels lit: the four sides only"
        );
        // An open top (hi y = +inf) has no lid; its sides rise to the extent's top (y = 9).
        let open = Scenery {
            colliders: vec![cuboid([2.0, 2.0, -1.0], [8.0, f64::INFINITY, 1.0])],
            extent: Some(([0.0, 0.0, 0.0], [10.0, 9.0, 0.0])),
        };
        let img = scene_frame(&cam, &[], &[], &[], &open, w, h);
        assert_eq!(pixel(&img, w, 50, 20), BG, "no lid at y = 8");
        assert_eq!(pixel(&img, w, 50, 80), LINE_COLOR, "the floor at y = 2");
        assert_eq!(pixel(&img, w, 20, 12), LINE_COLOR, "the left wall at y = 8.7");
        assert_eq!(pixel(&img, w, 20, 5), BG, "above the extent");
    }

    #[test]
    fn a_2d_plane_is_a_thick_line_with_its_solid_side_filled() {
        // The wall x = 5 with the free side towards +x, on pixel line 50; 3 px wide.
        let (w, h) = (100, 100);
        let cam = Camera::fit_2d([0.0, 0.0], [10.0, 10.0], w, h).unwrap();
        let wall = items(vec![plane([5.0, 0.0, 0.0], [2.0, 0.0, 0.0])]);
        let img = scene_frame(&cam, &[], &[], &[], &wall, w, h);
        for j in [0, 50, 99] {
            assert_eq!(pixel(&img, w, 49, j), LINE_COLOR);
            assert_eq!(pixel(&img, w, 50, j), LINE_COLOR);
            // 1.5 px from the centre line: clamp(1.5 + ½ − 1.5, 0, 1) = ½ of the line colour.
            let half = pixel(&img, w, 51, j);
            assert!((170..=180).contains(&half[0]), "{half:?}");
            assert_eq!(pixel(&img, w, 20, j), FLOOR_COLOR, "solid side");
            assert_eq!(pixel(&img, w, 80, j), BG, "free side");
        }
        // A plane parallel to the view (normal along z) has no line in 2D: nothing is drawn.
        let flat = items(vec![plane([0.0; 3], [0.0, 0.0, 1.0])]);
        assert!(scene_frame(&cam, &[], &[], &[], &flat, w, h).iter().all(|&b| b == 255));
    }

    #[test]
    fn a_3d_box_draws_its_edges_and_floor_and_an_open_one_has_no_lid() {
        let (w, h) = (200, 150);
        let cam = Camera::frame_box([-1.0, -1.0, 0.0], [1.0, 1.0, 2.0], [1.0, -1.6, 0.9], 40.0, w, h).unwrap();
        let closed = items(vec![cuboid([-1.0, -1.0, 0.0], [1.0, 1.0, 2.0])]);
        let open = items(vec![cuboid([-1.0, -1.0, 0.0], [1.0, 1.0, f64::INFINITY])]);
        // A particle at the top keeps the open box's extent at the closed box's height.
        let top = [[0.0, 0.0, 1.9]];
        let a = scene_frame(&cam, &top, &[0.1], &[[0, 0, 255]], &closed, w, h);
        let b = scene_frame(&cam, &top, &[0.1], &[[0, 0, 255]], &open, w, h);
        let count = |img: &[u8], c: [u8; 3]| img.chunks(3).filter(|p| *p == c).count();
        assert!(count(&a, LINE_COLOR) > 200, "edges drawn");
        assert!(count(&a, BOX_FLOOR_COLOR) > 1000, "floor face filled");
        assert_eq!(count(&a, BOX_FLOOR_COLOR), count(&b, BOX_FLOOR_COLOR), "the same floor");
        // The lid's four edges are missing from the open box, the rest is the same.
        assert!(count(&b, LINE_COLOR) < count(&a, LINE_COLOR) * 9 / 10);
        let differ = a.chunks(3).zip(b.chunks(3)).filter(|(p, q)| p != q).count();
        assert!(differ > 100);
    }

    // -- meshes -------------------------------------------------------------------------------

    fn mesh(vertices: Vec<[f64; 3]>, faces: Vec<[u32; 3]>) -> Collider {
        TriangleMesh::new(vertices, faces, false, Surface::default()).unwrap().into()
    }

    /// An equilateral triangle of circumradius `size` around `centre`, in the plane of normal `n`.
    fn triangle(centre: [f64; 3], n: [f64; 3], size: f64) -> Vec<[f64; 3]> {
        let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
        let n = n.map(|c| c / len);
        // t1 = n × z (or n × x when n is along z), t2 = n × t1.
        let a = if n[2].abs() < 0.9 { [0.0, 0.0, 1.0] } else { [1.0, 0.0, 0.0] };
        let cross = |a: [f64; 3], b: [f64; 3]| {
            [
                a[1] * b[2] - a[2] * b[1],
                a[2] * b[0] - a[0] * b[2],
                a[0] * b[1] - a[1] * b[0],
            ]
        };
        let t1 = cross(n, a);
        let l1 = (t1[0] * t1[0] + t1[1] * t1[1] + t1[2] * t1[2]).sqrt();
        let t1 = t1.map(|c| c / l1);
        let t2 = cross(n, t1);
        [90.0f64, 210.0, 330.0]
            .map(|deg| {
                let (s, c) = deg.to_radians().sin_cos();
                std::array::from_fn(|k| centre[k] + size * (c * t1[k] + s * t2[k]))
            })
            .to_vec()
    }

    #[test]
    fn a_mesh_is_translucent_and_what_is_behind_it_shows() {
        let (w, h) = (200, 150);
        let cam = Camera::perspective([0.0, -10.0, 0.0], [0.0; 3], [0.0, 0.0, 1.0], 40.0).unwrap();
        // A square of two triangles facing the camera, 4 m wide, filling the middle.
        let square = items(vec![mesh(
            vec![[-2.0, 0.0, -1.5], [2.0, 0.0, -1.5], [2.0, 0.0, 1.5], [-2.0, 0.0, 1.5]],
            vec![[0, 1, 2], [0, 2, 3]],
        )]);
        let mut params = RenderParams::new(w, h);
        params.background = [40, 60, 220];
        let mut img = vec![0u8; w * h * 3];
        render_scene(&cam, &[], &[], &[], &square, &params, &mut img).unwrap();
        let over_blue = pixel(&img, w, 100, 75);
        // Over white the square is a light grey, one layer thick: the same across its
        // diagonal (no seam where the triangles meet).
        let white = scene_frame(&cam, &[], &[], &[], &square, w, h);
        let (mid, seam) = (pixel(&white, w, 60, 100), pixel(&white, w, 100, 75));
        eprintln!("the mesh over blue {over_blue:?}, over white {mid:?}, on its diagonal {seam:?}");
        assert!(
            over_blue[2] > over_blue[0] + 80,
            "the background shows through: {over_blue:?}"
        );
        assert!(over_blue != params.background, "and is tinted");
        // Opacity: over white 255 (1 − α) + α c, over blue 220 (1 − α) + α c in the blue.
        let alpha = 1.0 - (mid[2] as f64 - over_blue[2] as f64) / (255.0 - 220.0);
        assert!((alpha - MESH_ALPHA as f64).abs() < 0.06, "opacity {alpha}");
        assert!(is_grey(mid, 10) && mid == seam, "one layer: {mid:?} {seam:?}");
        // A red ball behind it shows through, tinted; one in front is drawn over it, untinted.
        let red = [[220, 20, 20]];
        let alone = pixel(
            &scene_frame(&cam, &[[0.0, 2.0, 0.0]], &[0.4], &red, &items(vec![]), w, h),
            w,
            100,
            75,
        );
        let behind = pixel(
            &scene_frame(&cam, &[[0.0, 2.0, 0.0]], &[0.4], &red, &square, w, h),
            w,
            100,
            75,
        );
        let in_front = pixel(
            &scene_frame(&cam, &[[0.0, -2.0, 0.0]], &[0.3], &red, &square, w, h),
            w,
            100,
            75,
        );
        let in_front_alone = pixel(
            &scene_frame(&cam, &[[0.0, -2.0, 0.0]], &[0.3], &red, &items(vec![]), w, h),
            w,
            100,
            75,
        );
        eprintln!("ball alone {alone:?}, behind the mesh {behind:?}; in front {in_front:?} (alone {in_front_alone:?})");
        assert!(behind[0] > behind[1] + 60 && behind != alone, "tinted, still red: {behind:?}");
        assert_eq!(in_front, in_front_alone);
    }

    #[test]
    fn nearer_mesh_triangles_are_drawn_over_farther_ones_whatever_the_face_order() {
        let (w, h) = (200, 150);
        let cam = Camera::perspective([0.0, -10.0, 0.0], [0.0; 3], [0.0, 0.0, 1.0], 40.0).unwrap();
        // Two overlapping triangles, one facing the camera (lit: the light is in front, upper
        // left), one turned away from the light (the ambient shade, darker); each in turn the
        // nearer. Over white a single layer of colour c reads p = 255 (1 − α) + α c; the
        // nearer one over the farther one reads α c_near + (1 − α) p_far.
        let lit = |y: f64| triangle([0.0, y, 0.0], [0.0, -1.0, 0.0], 1.5);
        let dark = |y: f64| triangle([0.0, y, 0.0], [0.6, -0.5, -0.6], 1.5);
        let (p_lit, p_dark) = (
            pixel(
                &scene_frame(&cam, &[], &[], &[], &items(vec![mesh(lit(0.0), vec![[0, 1, 2]])]), w, h),
                w,
                100,
                75,
            ),
            pixel(
                &scene_frame(&cam, &[], &[], &[], &items(vec![mesh(dark(0.0), vec![[0, 1, 2]])]), w, h),
                w,
                100,
                75,
            ),
        );
        let a = MESH_ALPHA as f64;
        let tint = |p: [u8; 3]| p.map(|v| v as f64 - 255.0 * (1.0 - a)); // α c
        let over =
            |near: [u8; 3], far: [u8; 3]| -> [f64; 3] { std::array::from_fn(|k| tint(near)[k] + (1.0 - a) * far[k] as f64) };
        eprintln!("alone: lit {p_lit:?}, dark {p_dark:?}");
        assert!(luma(p_lit) > luma(p_dark) + 8.0, "Lambert: the lit face is lighter");
        for (lit_near, expected, wrong) in [
            (true, over(p_lit, p_dark), over(p_dark, p_lit)),
            (false, over(p_dark, p_lit), over(p_lit, p_dark)),
        ] {
            let (yl, yd) = if lit_near { (-2.0, 2.0) } else { (2.0, -2.0) };
            let mut vertices = lit(yl);
            vertices.extend(dark(yd));
            for faces in [vec![[0, 1, 2], [3, 4, 5]], vec![[3, 4, 5], [0, 1, 2]]] {
                let both = items(vec![mesh(vertices.clone(), faces)]);
                let c = pixel(&scene_frame(&cam, &[], &[], &[], &both, w, h), w, 100, 75);
                let off = |e: [f64; 3]| (0..3).map(|k| (c[k] as f64 - e[k]).abs()).fold(0.0, f64::max);
                eprintln!("lit nearer: {lit_near}: {c:?}, expected {expected:?}, the other order {wrong:?}");
                assert!(off(expected) <= 2.5 && off(wrong) >= 4.0, "{c:?}");
            }
        }
    }

    #[test]
    fn a_closed_cube_mesh_draws_its_edges_and_not_its_faces_diagonals() {
        let (w, h) = (240, 180);
        let cam = Camera::frame_box([-1.0; 3], [1.0; 3], [1.2, -1.6, 0.9], 40.0, w, h).unwrap();
        let corners: Vec<[f64; 3]> = (0..8)
            .map(|c| std::array::from_fn(|k| if c >> k & 1 == 1 { 1.0 } else { -1.0 }))
            .collect();
        // Two triangles per face (outward normals; the mesh orients a closed one anyway).
        let faces = vec![
            [0, 2, 3],
            [0, 3, 1],
            [4, 5, 7],
            [4, 7, 6], // z = −1, z = +1
            [0, 1, 5],
            [0, 5, 4],
            [2, 6, 7],
            [2, 7, 3], // y = −1, y = +1
            [0, 4, 6],
            [0, 6, 2],
            [1, 3, 7],
            [1, 7, 5], // x = −1, x = +1
        ];
        let cube = items(vec![mesh(corners, faces)]);
        let img = scene_frame(&cam, &[], &[], &[], &cube, w, h);
        let at = |p: [f64; 3]| {
            let q = project(&cam, p, w, h);
            pixel(&img, w, q[0] as usize, q[1] as usize)
        };
        // Seen from (+x, −y, +z): the faces x = 1, y = −1, z = 1 in front of the three others.
        // Each face is two triangles: the middle of its diagonal reads as the face does 4 px
        // to either side of it (two flat translucent layers, no line, no seam); its edges are
        // lines, darker.
        for (p, q) in [
            ([1.0, -1.0, -1.0], [1.0, 1.0, 1.0]),
            ([-1.0, -1.0, -1.0], [1.0, -1.0, 1.0]),
            ([-1.0, -1.0, 1.0], [1.0, 1.0, 1.0]),
        ] {
            let (a, b) = (project(&cam, p, w, h), project(&cam, q, w, h));
            let len = ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)).sqrt();
            let n = [(a[1] - b[1]) / len, (b[0] - a[0]) / len];
            let m = [0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1])];
            let px = |s: f64| pixel(&img, w, (m[0] + s * n[0]) as usize, (m[1] + s * n[1]) as usize);
            let (d, sides) = (px(0.0), [px(-4.0), px(4.0)]);
            eprintln!("diagonal {p:?}-{q:?}: {d:?}, beside it {sides:?}");
            for f in sides {
                assert!(
                    is_grey(f, 12) && (luma(d) - luma(f)).abs() <= 3.0,
                    "no line on the diagonal: {d:?} vs {f:?}"
                );
            }
        }
        let face = luma(at([1.0, 0.45, -0.45]));
        for e in [
            [1.0, -1.0, 0.0],
            [1.0, 0.0, 1.0],
            [0.0, -1.0, 1.0],
            [1.0, 0.0, -1.0],
            [-1.0, -1.0, 0.0],
        ] {
            let c = at(e);
            eprintln!("edge {e:?}: {c:?}");
            assert!(is_grey(c, 12) && luma(c) < face - 15.0, "a line on the edge at {e:?}: {c:?}");
        }
    }

    #[test]
    fn a_mesh_takes_contact_shadows_where_it_faces_up() {
        let (w, h) = (200, 150);
        let cam = Camera::perspective([0.0, -4.0, 4.0], [0.0, 0.0, 0.3], [0.0, 0.0, 1.0], 40.0).unwrap();
        // A square floor of two triangles, seen from above and from below.
        let floor = mesh(
            vec![[-3.0, -3.0, 0.0], [3.0, -3.0, 0.0], [3.0, 3.0, 0.0], [-3.0, 3.0, 0.0]],
            vec![[0, 1, 2], [0, 2, 3]],
        );
        let square = Scenery {
            colliders: vec![floor],
            extent: Some(([-3.0, -3.0, 0.0], [3.0, 3.0, 2.0])),
        };
        let r = 0.3;
        // The darkest luma and the count of the pixels darker by more than 4 than the same
        // frame with the ball out of sight (behind the eye, beside the mesh: no shadow, the
        // same radius and so the same pieces of the mesh), the ball's own pixels left out.
        let shadow = |cam: &Camera, centre: [f64; 3]| {
            let red = [[200, 30, 30]];
            let ball = scene_frame(cam, &[centre], &[r], &red, &items(vec![]), w, h);
            let away = scene_frame(cam, &[[0.0, -100.0, 50.0]], &[r], &red, &square, w, h);
            let img = scene_frame(cam, &[centre], &[r], &red, &square, w, h);
            let (mut darkest, mut count) = (255.0f64, 0);
            for j in 0..h {
                for i in 0..w {
                    let near_ball = (i.saturating_sub(2)..(i + 3).min(w))
                        .any(|x| (j.saturating_sub(2)..(j + 3).min(h)).any(|y| pixel(&ball, w, x, y) != BG));
                    let (l, l0) = (luma(pixel(&img, w, i, j)), luma(pixel(&away, w, i, j)));
                    if !near_ball && l < l0 - 4.0 {
                        darkest = darkest.min(l);
                        count += 1;
                    }
                }
            }
            (darkest, count)
        };
        let bare = luma(pixel(&scene_frame(&cam, &[], &[], &[], &square, w, h), w, 100, 75));
        let (rest_dark, rest_n) = shadow(&cam, [0.0, 0.0, r]);
        let (up_dark, up_n) = shadow(&cam, [0.0, 0.0, r + 1.0]);
        eprintln!("mesh floor {bare:.1}; resting: darkest {rest_dark:.1}, {rest_n} px; 1 m up: {up_dark:.1}, {up_n} px");
        assert!(
            rest_dark < bare - 40.0,
            "a shadow where the ball rests: {rest_dark} on {bare}"
        );
        assert!(
            up_dark > rest_dark + 20.0 && up_n > rest_n,
            "fainter and wider 1 m up: {up_dark}, {up_n} px"
        );
        // Seen from below (the ball above the mesh, seen through it) no shadow is drawn on
        // the mesh's far side; nor is one under a ball beside the mesh.
        let below = Camera::perspective([0.0, -4.0, -3.0], [0.0, 0.0, 0.0], [0.0, 0.0, 1.0], 40.0).unwrap();
        assert_eq!((shadow(&below, [0.0, 0.0, r]).1, shadow(&cam, [3.6, 0.0, r]).1), (0, 0));
    }

    #[test]
    fn a_mesh_passing_behind_the_eye_is_cut_at_the_near_distance() {
        // A large floor of two triangles 1 m below the eye, reaching far behind it: it fills
        // the lower half (cut, not wrapped around into the sky), as a plane would.
        let (w, h) = (160, 120);
        let cam = Camera::perspective([0.0, 0.0, 1.0], [0.0, 10.0, 1.0], [0.0, 0.0, 1.0], 60.0).unwrap();
        let floor = items(vec![mesh(
            vec![[-50.0, -50.0, 0.0], [50.0, -50.0, 0.0], [50.0, 50.0, 0.0], [-50.0, 50.0, 0.0]],
            vec![[0, 1, 2], [0, 2, 3]],
        )]);
        let img = scene_frame(&cam, &[], &[], &[], &floor, w, h);
        for j in 0..55 {
            assert!((0..w).all(|i| pixel(&img, w, i, j) == BG), "sky row {j} is background");
        }
        for j in 70..h {
            assert!((0..w).all(|i| is_grey(pixel(&img, w, i, j), 10)), "ground row {j} is mesh");
        }
    }

    /// A bar of 2 × 0.5 × 0.5 m along x centred at (0, 0, 0.25), as a closed mesh of 12
    /// triangles, each corner moved by `place`.
    fn bar(place: impl Fn([f64; 3]) -> [f64; 3]) -> Collider {
        let half = [1.0, 0.25, 0.25];
        let corners: Vec<[f64; 3]> = (0..8)
            .map(|k| {
                place(std::array::from_fn(|a| {
                    [0.0, 0.0, 0.25][a] + if k >> a & 1 == 1 { half[a] } else { -half[a] }
                }))
            })
            .collect();
        let faces = vec![
            [0, 2, 3],
            [0, 3, 1],
            [4, 5, 7],
            [4, 7, 6],
            [0, 1, 5],
            [0, 5, 4],
            [2, 6, 7],
            [2, 7, 3],
            [0, 4, 6],
            [0, 6, 2],
            [1, 3, 7],
            [1, 7, 5],
        ];
        mesh(corners, faces)
    }

    #[test]
    fn a_posed_scenery_draws_each_collider_where_its_pose_puts_it() {
        use kinema::collide::Pose;
        let (w, h) = (200, 150);
        let cam = Camera::perspective([1.0, -6.0, 4.0], [0.5, 0.0, 0.3], [0.0, 0.0, 1.0], 45.0).unwrap();
        let extent = Some(([-2.0, -2.0, -0.5], [3.0, 2.0, 1.5]));
        let (pos, r, red) = ([[0.0, 1.5, 0.6]], [0.15], [[200, 30, 30]]);
        // As added: a floor, a box, an obstacle and a bar along x, all at rest.
        let rest = Scenery {
            colliders: vec![
                plane([0.0, 0.0, -0.25], [0.0, 0.0, 1.0]),
                cuboid([-1.5, -1.0, -0.25], [-0.5, 0.0, 0.375]),
                obstacle([0.0, -1.0, 0.25], 0.25),
                bar(|p| p),
            ],
            extent,
        };
        // Posed: the floor, the box and the obstacle moved by t = (1, 0.5, 0.25), the bar
        // turned a quarter about z (about the origin) and moved by t: the scene built there
        // directly (every number a short binary fraction: the same bytes).
        let t = [1.0, 0.5, 0.25];
        let moved = Pose {
            rotation: Pose::IDENTITY.rotation,
            pivot: [0.0; 3],
            translation: t,
        };
        let turned = Pose {
            rotation: [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]],
            ..moved
        };
        let posed = rest.posed(&[moved, moved, moved, turned]).unwrap();
        assert_eq!(posed.extent, extent, "the extent is kept");
        let there = Scenery {
            colliders: vec![
                plane([1.0, 0.5, 0.0], [0.0, 0.0, 1.0]),
                cuboid([-0.5, -0.5, 0.0], [0.5, 0.5, 0.625]),
                obstacle([1.0, -0.5, 0.5], 0.25),
                bar(|[x, y, z]| [-y + t[0], x + t[1], z + t[2]]),
            ],
            extent,
        };
        let (a, b) = (
            scene_frame(&cam, &pos, &r, &red, &posed, w, h),
            scene_frame(&cam, &pos, &r, &red, &there, w, h),
        );
        let differ = (0..w * h).filter(|&k| a[3 * k..3 * k + 3] != b[3 * k..3 * k + 3]).count();
        assert_eq!(differ, 0, "pixels that differ from the scene built where the poses put it");
        assert_ne!(a, scene_frame(&cam, &pos, &r, &red, &rest, w, h), "the scene moved");
        // The identity keeps a collider as it is; a box turns not, and a pose per collider.
        assert_eq!(rest.posed(&[Pose::IDENTITY; 4]).unwrap(), rest);
        for (poses, name) in [(vec![moved, turned, moved, moved], "rotation"), (vec![moved], "poses")] {
            match rest.posed(&poses) {
                Err(Error::InvalidParameter { parameter, .. }) => assert_eq!(parameter, name),
                other => panic!("{other:?}"),
            }
        }
    }

    #[test]
    fn scenery_does_not_count_as_particles() {
        let cam = Camera::perspective([0.0, -10.0, 0.0], [0.0; 3], [0.0, 0.0, 1.0], 40.0).unwrap();
        let scenery = items(vec![obstacle([0.0; 3], 1.0), plane([0.0, 0.0, -1.0], [0.0, 0.0, 1.0])]);
        let mut image = vec![0u8; 64 * 64 * 3];
        let stats = render_scene(
            &cam,
            &[0.0, -3.0, 0.0],
            &[0.1],
            &[0; 3],
            &scenery,
            &RenderParams::new(64, 64),
            &mut image,
        )
        .unwrap();
        assert_eq!(stats, RenderStats { drawn: 1, culled: 0 });
    }

    #[test]
    fn bad_scenery_names_the_collider_field_and_the_extent() {
        // A collider is checked when it is made (the world's rules, collide/colliders.rs): a
        // bad one never reaches the renderer, and the error names the field and its value.
        let named = |e: Error| match e {
            Error::InvalidParameter {
                parameter,
                value,
                allowed,
            } => format!("{parameter} = {value}: {allowed}"),
            other => panic!("{other}"),
        };
        let s = Surface::default();
        let e = named(Plane::new([0.0; 3], [0.0; 3], s).unwrap_err());
        assert!(e.starts_with("normal = [0.0, 0.0, 0.0]") && e.contains("non-zero"), "{e}");
        let e = named(Plane::new([f64::INFINITY, 0.0, 0.0], [0.0, 0.0, 1.0], s).unwrap_err());
        assert!(e.starts_with("point[0]") && e.contains("finite"), "{e}");
        let e = named(Plane::new([0.0; 3], [f64::NAN, 0.0, 1.0], s).unwrap_err());
        assert!(e.starts_with("normal[0]"), "{e}");
        let e = named(SphereObstacle::new([0.0; 3], -0.5, s).unwrap_err());
        assert!(e.starts_with("radius = -0.5") && e.contains(">= 0"), "{e}");
        let e = named(SphereObstacle::new([f64::NAN, 0.0, 0.0], 1.0, s).unwrap_err());
        assert!(e.starts_with("center[0]"), "{e}");
        for (lo, hi, name) in [
            ([0.0, 0.0, 1.0], [1.0, 1.0, 1.0], "hi[2]"),                     // empty along z
            ([f64::NAN, 0.0, 0.0], [1.0; 3], "lo[0]"),                       // NaN
            ([0.0, f64::INFINITY, 0.0], [1.0, f64::INFINITY, 1.0], "lo[1]"), // lo = +inf
        ] {
            let e = named(BoxContainer::new(lo, hi, s).unwrap_err());
            assert!(e.starts_with(name), "{e}");
        }
        // The extent is the renderer's to check.
        let cam = Camera::fit_2d([0.0, 0.0], [1.0, 1.0], 10, 10).unwrap();
        let mut image = vec![0u8; 300];
        let p = RenderParams::new(10, 10);
        let fine = cuboid([f64::NEG_INFINITY, 0.0, 0.0], [1.0, 1.0, f64::INFINITY]);
        let bad = Scenery {
            colliders: vec![obstacle([0.0; 3], 1.0), fine.clone()],
            extent: Some(([0.0; 3], [f64::INFINITY, 1.0, 1.0])),
        };
        let e = named(render_scene(&cam, &[], &[], &[], &bad, &p, &mut image).unwrap_err());
        assert!(e.starts_with("extent"), "{e}");
        let ok = Scenery {
            colliders: vec![fine],
            extent: None,
        };
        render_scene(&cam, &[], &[], &[], &ok, &p, &mut image).unwrap();
    }

    #[test]
    fn a_video_extent_holds_every_frame_and_the_finite_scenery() {
        // Two frames of two particles (one not alive in the second: NaN), radii 0.1 and 0.25;
        // a box open at the top and a sphere obstacle of radius 1 at (5, 0, 0).
        let positions = [
            0.0,
            0.0,
            0.5,
            1.0,
            2.0,
            0.5, //
            0.5,
            -1.0,
            3.0,
            f64::NAN,
            f64::NAN,
            f64::NAN,
        ];
        let colliders = [
            cuboid([-1.0, -1.0, 0.0], [1.0, 1.0, f64::INFINITY]),
            obstacle([5.0, 0.0, 0.0], 1.0),
            plane([0.0; 3], [0.0, 0.0, 1.0]),
        ];
        let (lo, hi) = scene_extent(&positions, &[0.1, 0.25], &colliders).unwrap();
        // x: box −1, sphere 4 … 6; y: box ±1, particle 2; z: box floor 0, particle 3, sphere
        // ±1; every side widened by the largest radius, 0.25.
        assert_eq!(lo, [-1.25, -1.25, -1.25]);
        assert_eq!(hi, [6.25, 2.25, 3.25]);
        // The open top rises to the extent; the plane occupies no box.
        assert_eq!(
            collider_boxes(&colliders, (lo, hi)),
            vec![([-1.0, -1.0, 0.0], [1.0, 1.0, 3.25]), ([4.0, -1.0, -1.0], [6.0, 1.0, 1.0])]
        );
        // Nothing finite at all: the unit cube, widened by 1e-3 of its side; a single point
        // without radius: 0.5 m around it.
        let (lo, hi) = scene_extent(&[f64::NAN; 3], &[0.0], &[]).unwrap();
        assert_eq!((lo, hi), ([-0.001; 3], [1.001; 3]));
        let (lo, hi) = scene_extent(&[2.0, 0.0, 0.0], &[0.0], &[]).unwrap();
        assert_eq!((lo, hi), ([1.5, -0.5, -0.5], [2.5, 0.5, 0.5]));
        let e = scene_extent(&[0.0; 3], &[-1.0], &[]).unwrap_err();
        assert!(e.to_string().starts_with("radius[0] = -1 is invalid"), "{e}");
    }

    // -- springs ------------------------------------------------------------------------------

    fn spring_frame(
        camera: &Camera,
        pos: &[[f64; 3]],
        radius: &[f64],
        springs: &[[usize; 2]],
        scenery: &Scenery,
        w: usize,
        h: usize,
    ) -> Vec<u8> {
        let mut image = vec![0u8; w * h * 3];
        let positions: Vec<f64> = pos.iter().flatten().copied().collect();
        let colors: Vec<u8> = pos.iter().flat_map(|_| [200, 0, 0]).collect();
        let frame = Frame {
            springs,
            scenery,
            ..Frame::particles(&positions, radius, &colors)
        };
        render_frame(camera, &frame, &RenderParams::new(w, h), &mut image).unwrap();
        image
    }

    #[test]
    fn a_spring_is_a_line_from_rim_to_rim() {
        // [0, 10] × [0, 5] onto 200 × 100: 20 px per m. Two discs of radius 10 px on the row
        // whose pixel centres are at y = 49.5, x = 2 m and 8 m (pixel columns 40 and 160).
        let (w, h) = (200, 100);
        let cam = Camera::fit_2d([0.0, 0.0], [10.0, 5.0], w, h).unwrap();
        let pos = [[2.0, 2.525, 0.0], [8.0, 2.525, 0.0]];
        let img = spring_frame(&cam, &pos, &[0.5, 0.5], &[[0, 1]], &Scenery::default(), w, h);
        for i in 55..145 {
            assert_eq!(pixel(&img, w, i, 49), LINE_COLOR, "column {i} on the line");
        }
        // 1.5 px wide: the rows beside it are touched at most partly, the ones beyond not at all.
        assert_ne!(pixel(&img, w, 100, 48), LINE_COLOR);
        assert_eq!(pixel(&img, w, 100, 46), BG);
        assert_eq!(pixel(&img, w, 100, 52), BG);
        // The discs are whole: the line stops at their rims.
        assert_eq!(pixel(&img, w, 45, 49), [200, 0, 0]);
        assert_eq!(pixel(&img, w, 155, 49), [200, 0, 0]);
        // No spring, no line; a spring of one particle with itself draws nothing.
        let bare = spring_frame(&cam, &pos, &[0.5, 0.5], &[], &Scenery::default(), w, h);
        assert_eq!(pixel(&bare, w, 100, 49), BG);
        assert_eq!(
            spring_frame(&cam, &pos, &[0.5, 0.5], &[[1, 1]], &Scenery::default(), w, h),
            bare
        );
        // An index past the particles is an error that names the spring.
        let mut image = vec![0u8; w * h * 3];
        let frame = Frame {
            springs: &[[0, 1], [1, 2]],
            ..Frame::particles(&[0.0; 6], &[0.1; 2], &[0; 6])
        };
        let e = render_frame(&cam, &frame, &RenderParams::new(w, h), &mut image);
        match e.unwrap_err() {
            Error::InvalidParameter { parameter, .. } => assert_eq!(parameter, "springs[1]"),
            other => panic!("{other}"),
        }
    }

    #[test]
    fn a_3d_spring_in_front_of_an_obstacle_shows_and_one_behind_it_does_not() {
        // Looking along +y at a sphere obstacle of radius 1 at the origin; a horizontal spring
        // through x = 0 at y = −2 (in front, 8 m from the eye) or y = +2 (behind, 12 m), half a
        // pixel below the centre so that it runs along the centres of pixel row 100.
        let (w, h) = (200, 200);
        let cam = Camera::perspective([0.0, -10.0, 0.0], [0.0; 3], [0.0, 0.0, 1.0], 40.0).unwrap();
        let f = 100.0 / 20f64.to_radians().tan();
        let ball = items(vec![obstacle([0.0; 3], 1.0)]);
        let spring_at = |y: f64| {
            let z = -0.5 * (y + 10.0) / f;
            spring_frame(&cam, &[[-2.0, y, z], [2.0, y, z]], &[0.05; 2], &[[0, 1]], &ball, w, h)
        };
        let (front, behind) = (spring_at(-2.0), spring_at(2.0));
        let count = |img: &[u8]| (0..w).filter(|&i| pixel(img, w, i, 100) == LINE_COLOR).count();
        assert_eq!(pixel(&front, w, 100, 100), LINE_COLOR, "drawn over the obstacle");
        assert!(
            is_grey(pixel(&behind, w, 100, 100), 12) && pixel(&behind, w, 100, 100) != LINE_COLOR,
            "hidden by it"
        );
        assert!(count(&front) > count(&behind) + 40, "{} vs {}", count(&front), count(&behind));
        assert!(count(&behind) > 10, "beside the obstacle the far spring shows");
    }

    // -- framing ------------------------------------------------------------------------------

    /// Pixel position of a world point under a perspective camera (the pinhole of camera.rs).
    fn project(cam: &Camera, p: [f64; 3], w: usize, h: usize) -> [f64; 2] {
        let Camera::Perspective {
            eye,
            target,
            up,
            fov_y_deg,
            ..
        } = *cam
        else {
            panic!()
        };
        let sub = |a: [f64; 3], b: [f64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
        let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        let cross = |a: [f64; 3], b: [f64; 3]| {
            [
                a[1] * b[2] - a[2] * b[1],
                a[2] * b[0] - a[0] * b[2],
                a[0] * b[1] - a[1] * b[0],
            ]
        };
        let unit = |a: [f64; 3]| {
            let n = dot(a, a).sqrt();
            [a[0] / n, a[1] / n, a[2] / n]
        };
        let f_ = unit(sub(target, eye));
        let r = unit(cross(f_, up));
        let u = cross(r, f_);
        let d = sub(p, eye);
        let f = 0.5 * h as f64 / (0.5 * fov_y_deg.to_radians()).tan();
        let z = dot(d, f_);
        [0.5 * w as f64 + f * dot(d, r) / z, 0.5 * h as f64 - f * dot(d, u) / z]
    }

    #[test]
    fn frame_box_fits_a_tall_box_and_a_wide_one_into_both_fields_of_view() {
        let (w, h) = (320, 180);
        for (hi, tall) in [([0.5, 0.5, 3.0], true), ([4.0, 4.0, 0.2], false)] {
            let lo = [0.0; 3];
            let cam = Camera::frame_box(lo, hi, [1.0, -1.6, 0.9], 40.0, w, h).unwrap();
            let corners: Vec<[f64; 2]> = (0..8)
                .map(|c| {
                    project(
                        &cam,
                        std::array::from_fn(|k| if c >> k & 1 == 1 { hi[k] } else { lo[k] }),
                        w,
                        h,
                    )
                })
                .collect();
            let (x0, x1) = corners
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| (a.min(p[0]), b.max(p[0])));
            let (y0, y1) = corners
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| (a.min(p[1]), b.max(p[1])));
            let (mw, mh) = (FRAME_MARGIN * w as f64, FRAME_MARGIN * h as f64);
            let tol = 1e-6;
            assert!(
                x0 >= mw - tol && x1 <= w as f64 - mw + tol && y0 >= mh - tol && y1 <= h as f64 - mh + tol,
                "{x0} {x1} {y0} {y1}"
            );
            // The binding side is filled to its margins, the other centred.
            let (fill_x, fill_y) = ((x1 - x0) / (w as f64 - 2.0 * mw), (y1 - y0) / (h as f64 - 2.0 * mh));
            assert!((fill_x.max(fill_y) - 1.0).abs() < 1e-6, "{fill_x} {fill_y}");
            assert!(if tall { fill_y > fill_x } else { fill_x > fill_y });
            assert!((0.5 * (x0 + x1) - 0.5 * w as f64).abs() < 1e-6 && (0.5 * (y0 + y1) - 0.5 * h as f64).abs() < 1e-6);
        }
        // A window off-centre: the points go into it.
        let pts = [[0.0, 0.0, 0.0], [1.0, 1.0, 1.0]];
        let (cam, bbox) = Camera::frame_points(&pts, [1.0, -1.0, 1.0], 40.0, w, h, [10.0, 20.0, 200.0, 170.0]).unwrap();
        for p in pts {
            let q = project(&cam, p, w, h);
            assert!(q[0] >= bbox[0] - 1e-6 && q[0] <= bbox[2] + 1e-6 && q[1] >= bbox[1] - 1e-6 && q[1] <= bbox[3] + 1e-6);
        }
        assert!(
            bbox[0] >= 10.0 - 1e-6 && bbox[2] <= 200.0 + 1e-6 && bbox[1] >= 20.0 - 1e-6 && bbox[3] <= 170.0 + 1e-6,
            "{bbox:?}"
        );
        assert!(Camera::frame_points(&pts, [1.0, 0.0, 0.0], 40.0, w, h, [10.0, 20.0, 5.0, 170.0]).is_err());
    }

    #[test]
    fn a_trail_follows_the_path_and_fades_and_a_marker_is_an_amber_disc() {
        // [0, 10] × [0, 5] onto 200 × 100: 20 px per m. One particle at (8, 2.5) that came
        // along the row y = 2.5 from x = 2: its trail runs left of it, oldest (faintest) first.
        let (w, h) = (200, 100);
        let cam = Camera::fit_2d([0.0, 0.0], [10.0, 5.0], w, h).unwrap();
        let trail: Vec<f64> = (0..7).flat_map(|k| [2.0 + k as f64, 2.525, 0.0]).collect();
        let marker = [5.0, 4.0, 0.0];
        let frame = Frame {
            trails: &trail,
            trail_len: 7,
            markers: &marker,
            ..Frame::particles(&[8.0, 2.525, 0.0], &[0.25], &[200, 0, 0])
        };
        let mut img = vec![0u8; w * h * 3];
        render_frame(&cam, &frame, &RenderParams::new(w, h), &mut img).unwrap();
        // Newest segment (x 7 → 8 m): the particle's colour; oldest (2 → 3 m): faint.
        let (new, old) = (pixel(&img, w, 150, 49), pixel(&img, w, 50, 49));
        assert_eq!(new, [200, 0, 0], "the newest segment has the particle's colour");
        assert!(old[0] > 240 && old[1] > 200, "{old:?}");
        assert_eq!(pixel(&img, w, 100, 40), BG, "nothing off the path");
        // The marker: amber at (5, 4) m → pixel (100, 20), a dark rim 6 px out.
        assert_eq!(pixel(&img, w, 100, 20), kinema::render::MARKER_COLOR);
        let rim = pixel(&img, w, 105, 20);
        assert!(rim.iter().all(|&c| c < 120), "{rim:?}");
        // A trail of the wrong length is an error that names it.
        let bad = Frame { trail_len: 6, ..frame };
        match render_frame(&cam, &bad, &RenderParams::new(w, h), &mut img).unwrap_err() {
            Error::InvalidParameter { parameter, .. } => assert_eq!(parameter, "trails"),
            other => panic!("{other}"),
        }
    }
}
