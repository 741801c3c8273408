//! The renderer draws what it should: discs where they are with antialiased edges, nearer
//! spheres over farther ones, perspective sizes, nothing behind the eye, and the same bytes
//! for every thread count.

// The tests sit in a module named `render` so that `cargo test render` selects them.
mod render {
    use kinema::render::{render, text, Camera, RenderParams, RenderStats};
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
        let (w, h) = (320, 200);
        let params = RenderParams::new(w, h);
        let cams = [
            Camera::frame_box([0.0; 3], [1.0; 3], [1.0, -1.5, 0.8], 40.0, w, h).unwrap(),
            Camera::fit_2d([0.0, 0.0], [1.0, 1.0], w, h).unwrap(),
        ];
        for cam in cams {
            let images: Vec<Vec<u8>> = [1, 2, 3]
                .iter()
                .map(|&threads| {
                    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
                    let mut image = vec![0u8; w * h * 3];
                    pool.install(|| render(&cam, &positions, &radius, &colors, &params, &mut image))
                        .unwrap();
                    image
                })
                .collect();
            assert!(images[0].iter().any(|&b| b != 255));
            assert_eq!(images[0], images[1], "1 vs 2 threads, {cam:?}");
            assert_eq!(images[0], images[2], "1 vs 3 threads, {cam:?}");
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
}
