//! The mesh collider's geometry against hand-computed cases and brute force.

use super::features::closest_on_triangle;
use super::hierarchy::node_count;
use super::*;

/// The unit cube [0, 1]³ as 12 triangles, wound `outwards` (counter-clockwise seen from
/// outside) or inwards.
pub(crate) fn cube(outwards: bool) -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
    let v: Vec<[f64; 3]> = (0..8)
        .map(|k| [(k & 1) as f64, ((k >> 1) & 1) as f64, ((k >> 2) & 1) as f64])
        .collect();
    // each face as a quad (a, b, c, d) counter-clockwise from outside
    let quads = [
        [0, 2, 3, 1], // z = 0, normal −z
        [4, 5, 7, 6], // z = 1
        [0, 1, 5, 4], // y = 0
        [2, 6, 7, 3], // y = 1
        [0, 4, 6, 2], // x = 0
        [1, 3, 7, 5], // x = 1
    ];
    let mut f = Vec::new();
    for [a, b, c, d] in quads {
        for tri in [[a, b, c], [a, c, d]] {
            f.push(if outwards { tri } else { [tri[0], tri[2], tri[1]] });
        }
    }
    (v, f)
}

fn touches(m: &TriangleMesh, p: [f64; 3], r: f64) -> Vec<Touch> {
    let mut out = Vec::new();
    m.for_each_touch(p, r, 0.0, |t| out.push(t));
    out
}

fn close(a: [f64; 3], b: [f64; 3]) -> bool {
    (0..3).all(|k| (a[k] - b[k]).abs() < 1e-14)
}

#[test]
fn closest_point_regions_by_hand() {
    let (a, b, c) = ([0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 2.0, 0.0]);
    assert_eq!(
        closest_on_triangle([0.5, 0.5, 3.0], a, b, c),
        ([0.5, 0.5, 0.0], Feature::Face)
    );
    assert_eq!(closest_on_triangle([-1.0, -1.0, 1.0], a, b, c), (a, Feature::Vertex(0)));
    assert_eq!(closest_on_triangle([3.0, -0.5, 0.0], a, b, c), (b, Feature::Vertex(1)));
    assert_eq!(
        closest_on_triangle([1.0, -1.0, 0.5], a, b, c),
        ([1.0, 0.0, 0.0], Feature::Edge(0))
    );
    // beyond the hypotenuse x + y = 2: the foot on it
    assert_eq!(
        closest_on_triangle([2.0, 2.0, 0.0], a, b, c),
        ([1.0, 1.0, 0.0], Feature::Edge(1))
    );
}

#[test]
fn a_closed_mesh_is_oriented_outwards_and_knows_inside() {
    for outwards in [true, false] {
        let (v, f) = cube(outwards);
        let m = TriangleMesh::new(v, f, false, Surface::default()).unwrap();
        assert!(m.is_closed());
        assert_eq!(m.side(), Side::Outside);
        // face 0 lies on z = 0: its outward normal is −z whatever the winding given
        assert_eq!(m.face_normal(0), [0.0, 0.0, -1.0]);
        assert!(m.contains([0.5, 0.5, 0.5]));
        assert!(m.contains([0.01, 0.99, 0.5]));
        assert!(!m.contains([1.5, 0.5, 0.5]));
        assert!(!m.contains([0.5, 0.5, -0.01]));
    }
    // one face removed: open, two-sided, and no inside to ask for
    let (v, mut f) = cube(true);
    f.pop();
    let open = TriangleMesh::new(v.clone(), f.clone(), false, Surface::default()).unwrap();
    assert_eq!((open.is_closed(), open.side()), (false, Side::Both));
    let e = TriangleMesh::new(v, f, true, Surface::default()).unwrap_err().to_string();
    assert!(
        e.starts_with("inside = true is invalid: only a closed mesh has an inside"),
        "{e}"
    );
}

#[test]
fn a_flat_patch_of_triangles_gives_one_contact_at_its_seams() {
    // The top of the cube (z = 1) is two triangles with the seam along its diagonal, and four
    // convex edges. A ball resting on it (overlap 0.01) anywhere on the face, at the seam
    // and at the middle of the square, touches the face only: one contact, normal +z.
    let (v, f) = cube(true);
    let m = TriangleMesh::new(v, f, false, Surface::default()).unwrap();
    for p in [[0.5, 0.5, 1.09], [0.3, 0.3, 1.09], [0.2, 0.7, 1.09], [0.95, 0.5, 1.09]] {
        let t = touches(&m, p, 0.1);
        assert_eq!(t.len(), 1, "{p:?}: {t:?}");
        assert!(close(t[0].normal, [0.0, 0.0, 1.0]), "{p:?}: {t:?}");
        assert!((t[0].overlap - 0.01).abs() < 1e-14, "{p:?}: {t:?}");
    }
}

#[test]
fn a_ball_over_a_seam_or_a_fan_apex_touches_once() {
    // A flat grid of 20 x 20 squares (two triangles each) at z = 0: a ball centred exactly
    // over a diagonal seam, over a square's corner (where 6 triangles meet) and over an edge
    // between squares touches the patch once, along +z, overlap 0.001.
    let k = 20u32;
    let mut v = Vec::new();
    for j in 0..=k {
        for i in 0..=k {
            v.push([i as f64 * 0.05, j as f64 * 0.05, 0.0]);
        }
    }
    let mut f = Vec::new();
    for j in 0..k {
        for i in 0..k {
            let a = j * (k + 1) + i;
            f.push([a, a + 1, a + k + 2]);
            f.push([a, a + k + 2, a + k + 1]);
        }
    }
    let grid = TriangleMesh::new(v, f, false, Surface::default()).unwrap();
    for p in [
        [0.1125, 0.1125, 0.019],
        [0.15, 0.25, 0.019],
        [0.125, 0.2, 0.019],
        [0.37, 0.41, 0.019],
    ] {
        let t = touches(&grid, p, 0.02);
        assert_eq!(t.len(), 1, "{p:?}: {t:?}");
        assert!(
            close(t[0].normal, [0.0, 0.0, 1.0]) && (t[0].overlap - 0.001).abs() < 1e-14,
            "{p:?}: {t:?}"
        );
    }
    // The pole of a shallow cone of 200 thin triangles (a UV sphere's cap): a ball resting
    // at the apex is tangent to every spoke (200 face contacts tilted 5.7°, rule 2 keeps
    // them all); rule 3 makes them one, along the axis by symmetry. Off the axis, one or two.
    let n = 200u32;
    let mut v = vec![[0.0, 0.0, 0.0]];
    for s in 0..n {
        let a = std::f64::consts::TAU * s as f64 / n as f64;
        v.push([0.1 * a.cos(), 0.1 * a.sin(), 0.01]);
    }
    let f: Vec<[u32; 3]> = (0..n).map(|s| [0, 1 + s, 1 + (s + 1) % n]).collect();
    let cone = TriangleMesh::new(v, f, false, Surface::default()).unwrap();
    let t = touches(&cone, [0.0, 0.0, 0.0199], 0.02);
    assert_eq!(t.len(), 1, "{t:?}");
    assert!(t[0].normal[2] > 1.0 - 1e-12, "{t:?}");
    let t = touches(&cone, [0.003, 0.001, 0.02], 0.02);
    assert!((1..=2).contains(&t.len()), "{} contacts", t.len());
}

#[test]
fn convex_edges_and_corners_give_their_own_normal() {
    // Outside the cube beyond the edge x = 1, z = 1 along (1, 0, 1)/√2, and beyond the corner
    // (1, 1, 1) along (1, 1, 1)/√3: one contact each, from the feature to the centre.
    let (v, f) = cube(true);
    let m = TriangleMesh::new(v, f, false, Surface::default()).unwrap();
    let (r, d) = (0.1, 0.09);
    let s2 = std::f64::consts::FRAC_1_SQRT_2;
    let edge = touches(&m, [1.0 + d * s2, 0.5, 1.0 + d * s2], r);
    assert_eq!(edge.len(), 1, "{edge:?}");
    assert!(close(edge[0].normal, [s2, 0.0, s2]), "{edge:?}");
    assert!((edge[0].overlap - (r - d)).abs() < 1e-14);
    let s3 = 1.0 / 3f64.sqrt();
    let corner = touches(&m, [1.0 + d * s3, 1.0 + d * s3, 1.0 + d * s3], r);
    assert_eq!(corner.len(), 1, "{corner:?}");
    assert!(close(corner[0].normal, [s3, s3, s3]), "{corner:?}");
    // inside the cube as a container, in its corner: three faces, the inward normals
    let (v, f) = cube(true);
    let inside = TriangleMesh::new(v, f, true, Surface::default()).unwrap();
    let mut got: Vec<[f64; 3]> = touches(&inside, [0.95, 0.95, 0.95], r).iter().map(|t| t.normal).collect();
    got.sort_by(|a, b| a.partial_cmp(b).unwrap());
    assert_eq!(got, vec![[-1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, -1.0]]);
}

#[test]
fn a_centre_pushed_past_a_closed_mesh_face_is_pushed_back_out() {
    // A centre 0.05 inside the cube below its top face: the obstacle's normal is still +z,
    // the overlap r + 0.05; two-sided (the open cube), the centre's own side, −z.
    let (v, f) = cube(true);
    let m = TriangleMesh::new(v, f, false, Surface::default()).unwrap();
    let t = touches(&m, [0.5, 0.4, 0.95], 0.1);
    assert_eq!(t.len(), 1, "{t:?}");
    assert!(close(t[0].normal, [0.0, 0.0, 1.0]));
    assert!((t[0].overlap - 0.15).abs() < 1e-14);
    let top = TriangleMesh::new(
        vec![[0.0, 0.0, 1.0], [1.0, 0.0, 1.0], [1.0, 1.0, 1.0], [0.0, 1.0, 1.0]],
        vec![[0, 1, 2], [0, 2, 3]],
        false,
        Surface::default(),
    )
    .unwrap();
    let t = touches(&top, [0.5, 0.4, 0.95], 0.1);
    assert_eq!(t.len(), 1, "{t:?}");
    assert!(close(t[0].normal, [0.0, 0.0, -1.0]));
    assert!((t[0].overlap - 0.05).abs() < 1e-14);
}

#[test]
fn a_concave_crease_gives_both_faces() {
    // A V of two half-planes z = |x| tan 30° (as triangles far larger than the ball): a ball
    // in the crease touches both faces, each with its own normal.
    let t30 = (30f64).to_radians().tan();
    let v = vec![
        [-10.0, -10.0, 10.0 * t30],
        [-10.0, 10.0, 10.0 * t30],
        [0.0, -10.0, 0.0],
        [0.0, 10.0, 0.0],
        [10.0, -10.0, 10.0 * t30],
        [10.0, 10.0, 10.0 * t30],
    ];
    let f = vec![[0, 2, 3], [0, 3, 1], [2, 4, 5], [2, 5, 3]];
    let m = TriangleMesh::new(v, f, false, Surface::default()).unwrap();
    let r = 0.1;
    // the ball centred on the axis at the height where it overlaps each face by 0.01
    let z = (r - 0.01) / (30f64).to_radians().cos();
    let t = touches(&m, [0.0, 0.5, z], r);
    assert_eq!(t.len(), 2, "{t:?}");
    let (s, c) = ((30f64).to_radians().sin(), (30f64).to_radians().cos());
    let mut normals: Vec<[f64; 3]> = t.iter().map(|t| t.normal).collect();
    normals.sort_by(|a, b| a.partial_cmp(b).unwrap());
    assert!(
        close(normals[0], [-s, 0.0, c]) && close(normals[1], [s, 0.0, c]),
        "{normals:?}"
    );
    for t in &t {
        assert!((t.overlap - 0.01).abs() < 1e-14, "{t:?}");
    }
}

#[test]
fn continuous_detection_stops_a_fast_ball_at_a_thin_shell() {
    // A zero-thickness square at z = 0 (a shell thinner than any 1 mm one); a ball r = 0.01 at z = 0.5 falling at
    // 100 m/s crosses it within a 10 ms step. It meets the face at τ = (0.5 − 0.01)/100, and
    // from below symmetrically (two-sided); sideways, a ball passing the square's edge
    // meets the edge's cylinder when its centre is r from the edge.
    let sq = TriangleMesh::new(
        vec![[-1.0, -1.0, 0.0], [1.0, -1.0, 0.0], [1.0, 1.0, 0.0], [-1.0, 1.0, 0.0]],
        vec![[0, 1, 2], [0, 2, 3]],
        false,
        Surface::default(),
    )
    .unwrap();
    let (t, _) = sq.toi([0.2, 0.1, 0.5], [0.0, 0.0, -100.0], [0.0; 3], 0.01, 0.01).unwrap();
    assert!((t - 0.49 / 100.0).abs() < 1e-16, "{t}");
    let (t, _) = sq.toi([0.2, 0.1, -0.5], [0.0, 0.0, 100.0], [0.0; 3], 0.01, 0.01).unwrap();
    assert!((t - 0.49 / 100.0).abs() < 1e-16, "{t}");
    assert!(sq.toi([0.2, 0.1, 0.5], [0.0, 0.0, -100.0], [0.0; 3], 0.01, 0.004).is_none());
    // grazing past the edge x = 1 at height 0.005: contact when the centre is 0.01 from the
    // edge's line, x = 1 + √(0.01² − 0.005²)
    let (t, _) = sq.toi([2.0, 0.0, 0.005], [-100.0, 0.0, 0.0], [0.0; 3], 0.01, 0.1).unwrap();
    let want = (1.0 - (0.01f64.powi(2) - 0.005f64.powi(2)).sqrt()) / 100.0;
    assert!((t - want).abs() < 1e-15, "{t} vs {want}");
    // a ball sliding on the square across its diagonal seam meets nothing
    assert!(sq.toi([-0.5, -0.6, 0.0099], [10.0, 10.0, 0.0], [0.0; 3], 0.01, 0.1).is_none());
}

#[test]
fn the_hierarchy_finds_what_brute_force_finds() {
    // A wavy sheet of 2 × 40 × 40 triangles: for 300 random spheres the touches through
    // the hierarchy equal those of every triangle tested (before the ghost rules).
    let k = 40;
    let mut v = Vec::new();
    for j in 0..=k {
        for i in 0..=k {
            let (x, y) = (i as f64 / k as f64, j as f64 / k as f64);
            v.push([x, y, 0.1 * (7.0 * x).sin() * (5.0 * y).cos()]);
        }
    }
    let mut f = Vec::new();
    for j in 0..k as u32 {
        for i in 0..k as u32 {
            let a = j * (k as u32 + 1) + i;
            f.push([a, a + 1, a + k as u32 + 2]);
            f.push([a, a + k as u32 + 2, a + k as u32 + 1]);
        }
    }
    let m = TriangleMesh::new(v, f, false, Surface::default()).unwrap();
    let mut rnd = uniform(7);
    let mut hits = 0;
    for _ in 0..300 {
        let p = [rnd(), rnd(), 0.3 * rnd() - 0.15];
        let r = 0.05 * rnd();
        let mut fast = Vec::new();
        m.geometry
            .visit([p[0] - r, p[1] - r, p[2] - r], [p[0] + r, p[1] + r, p[2] + r], |t| {
                if m.near(t, p, r).is_some() {
                    fast.push(t);
                }
            });
        fast.sort_unstable();
        let slow: Vec<usize> = (0..m.faces().len()).filter(|&t| m.near(t, p, r).is_some()).collect();
        assert_eq!(fast, slow, "{p:?} r {r}");
        hits += slow.len();
    }
    assert!(hits > 100, "the spheres touch the sheet: {hits}");
}

#[test]
fn the_hierarchy_has_as_many_nodes_as_counted_so_its_buffer_never_grows() {
    // `node_count` sizes the nodes' buffer, allocated fallibly once: `split` must push exactly
    // that many (a push beyond it would grow the buffer infallibly, an abort when out of memory)
    for n in (1..200).chain([1000, 4097, 99_999]) {
        let v: Vec<[f64; 3]> = (0..n + 2).map(|k: usize| [k as f64, (k % 7 * (k % 5)) as f64, 0.0]).collect();
        let f: Vec<[u32; 3]> = (0..n as u32).map(|k| [k, k + 1, k + 2]).collect();
        let m = TriangleMesh::new(v, f, false, Surface::default()).unwrap();
        let faces = m.faces().len();
        assert_eq!(m.geometry.nodes.len(), node_count(faces), "{faces} triangles");
        assert_eq!(m.geometry.nodes.capacity(), node_count(faces), "{faces} triangles");
    }
}

#[test]
fn a_mesh_buffer_beyond_memory_is_the_meshs_out_of_memory_error() {
    let e = mesh_buffer::<[f64; 3]>(usize::MAX / 8, 12_345).unwrap_err();
    assert!(matches!(e, Error::OutOfMemory { .. }), "{e:?}");
    assert_eq!(
        e.to_string(),
        format!(
            "a mesh of 12345 triangles (about {BYTES_PER_TRIANGLE} B each while it is built) needs about 0.001 GiB of memory, \
             which cannot be allocated"
        )
    );
}

/// Uniform numbers in [0, 1) from a 64-bit linear congruential generator seeded with `seed`
/// (Knuth's MMIX constants; the top 53 bits).
fn uniform(mut seed: u64) -> impl FnMut() -> f64 {
    move || {
        seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (seed >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// A k × k grid of squares of side `cell` (two triangles each) in the plane z = `height(i, j)`
/// of each vertex, wound counter-clockwise from +z.
fn sheet(k: u32, cell: f64, height: impl Fn(u32, u32) -> f64) -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
    let mut v = Vec::new();
    for j in 0..=k {
        for i in 0..=k {
            v.push([i as f64 * cell, j as f64 * cell, height(i, j)]);
        }
    }
    let mut f = Vec::new();
    for j in 0..k {
        for i in 0..k {
            let a = j * (k + 1) + i;
            f.push([a, a + 1, a + k + 2]);
            f.push([a, a + k + 2, a + k + 1]);
        }
    }
    (v, f)
}

/// The unit cube with each face cut into k × k squares of two triangles, counter-clockwise
/// from outside (vertices repeated along the cube's edges are welded).
fn fine_cube(k: u32) -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
    let mut v: Vec<[f64; 3]> = Vec::new();
    let mut index = std::collections::HashMap::new();
    let mut at = |p: [f64; 3]| {
        let key = p.map(|c| (c * k as f64).round() as i64);
        *index.entry(key).or_insert_with(|| {
            v.push(p);
            (v.len() - 1) as u32
        })
    };
    let frames: [([f64; 3], [f64; 3], [f64; 3]); 6] = [
        ([0.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]),
        ([0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]),
        ([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]),
        ([0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]),
        ([0.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, 1.0, 0.0]),
        ([1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]),
    ];
    let mut f = Vec::new();
    for (o, a, b) in frames {
        let p = |i: u32, j: u32| {
            let (s, u) = (i as f64 / k as f64, j as f64 / k as f64);
            [0, 1, 2].map(|c| o[c] + s * a[c] + u * b[c])
        };
        for j in 0..k {
            for i in 0..k {
                let q = [at(p(i, j)), at(p(i + 1, j)), at(p(i + 1, j + 1)), at(p(i, j + 1))];
                f.push([q[0], q[1], q[2]]);
                f.push([q[0], q[2], q[3]]);
            }
        }
    }
    (v, f)
}

/// Meshes of flat patches with the features the flat nodes must get right: a flat floor, a
/// terrace (two floors joined by a wall, a crease and a convex edge), a floor with one raised
/// vertex (all 40 x 40 squares of 2.5 cm), and a finely cut cube from inside and outside.
fn flat_patched_meshes() -> [(&'static str, TriangleMesh); 5] {
    let floor = sheet(40, 0.025, |_, _| 0.0);
    let terrace = sheet(40, 0.025, |i, _| if i > 20 { 0.1 } else { 0.0 });
    let bump = sheet(40, 0.025, |i, j| if (i, j) == (13, 17) { 0.01 } else { 0.0 });
    let cube = fine_cube(24);
    let mesh = |(v, f): (Vec<[f64; 3]>, Vec<[u32; 3]>), inside| TriangleMesh::new(v, f, inside, Surface::default()).unwrap();
    [
        ("floor", mesh(floor, false)),
        ("terrace", mesh(terrace, false)),
        ("bump", mesh(bump, false)),
        ("cube inside", mesh(cube.clone(), true)),
        ("cube outside", mesh(cube, false)),
    ]
}

/// Sphere number `case` against mesh `name` of [`flat_patched_meshes`]: its centre, radius
/// and tolerance (m), at random from `rnd`: radii from a fifth of a grid cell to 12 cells,
/// one case in three centred over a vertex or a seam's midpoint of the grid, a sheet's
/// spheres just touching it or overlapping it a little; tolerance 0, r/10 or r.
fn sphere_case(name: &str, case: usize, rnd: &mut impl FnMut() -> f64) -> ([f64; 3], f64, f64) {
    let cell = 1.0 / 40.0;
    let r = cell * [0.2, 1.0, 3.0, 12.0][case % 4] * (0.5 + rnd());
    let mut p = [rnd() * 1.2 - 0.1, rnd() * 1.2 - 0.1, rnd() * 1.2 - 0.1];
    if case % 3 == 0 {
        for (c, pc) in p.iter_mut().enumerate() {
            *pc = (*pc / cell).round() * cell + [0.0, 0.5 * cell][case / 3 % 2] * (c == 0) as u8 as f64;
        }
    }
    if !name.starts_with("cube") {
        p[2] = [0.0, 0.1][(p[0] > 0.5 && name == "terrace") as usize] + r * (0.7 + 0.35 * rnd());
    }
    (p, r, [0.0, 0.1 * r, r][case % 3])
}

#[test]
fn the_flat_nodes_leave_out_only_triangles_that_give_no_contact() {
    // For spheres at random (many centred over vertices and seams) the search that goes past
    // the flat nodes finds exactly what the search of every triangle within reach finds:
    // the same triangles, touches, points and features, bit for bit. Over a flat floor, a
    // terrace (two floors joined by a wall, a crease and a convex edge), a floor with one
    // raised vertex, and a finely cut cube from inside and outside.
    let meshes = flat_patched_meshes();
    let mut rnd = uniform(51);
    for (name, m) in &meshes {
        assert!(
            m.geometry.nodes.iter().any(|n| n.is_flat()),
            "{name}: a mesh of flat patches has flat nodes"
        );
        let (mut contacts, mut fewer) = (0, 0);
        for case in 0..2500 {
            let (p, r, tolerance) = sphere_case(name, case, &mut rnd);
            let got = m.touches(p, r, tolerance);
            let want = m.touches_everywhere(p, r, tolerance);
            assert_eq!(got, want, "{name}: p {p:?} r {r} tolerance {tolerance}");
            contacts += want.len();
            let (mut visited, mut all) = (0, 0);
            let (reach, margin) = (r + tolerance, 8.0 * m.eps(p, r));
            let (lo, hi) = (p.map(|c| c - reach), p.map(|c| c + reach));
            m.geometry
                .visit_past_flat(lo, hi, |flat| flat.holds_foot(p, reach, margin), |_| visited += 1);
            m.geometry.visit(lo, hi, |_| all += 1);
            fewer += (visited < all) as usize;
        }
        assert!(contacts > 1000, "{name}: the spheres touch the mesh: {contacts}");
        assert!(fewer > 100, "{name}: the flat nodes leave triangles out: {fewer}");
    }
}

#[test]
fn the_triangles_kept_near_a_point_answer_as_the_search_does_for_every_centre_within_their_slack() {
    // NearCache: the touches from the triangles gathered around a point are those of the
    // search from the root, bit for bit, for centres within the slack of that point along
    // each axis (its corners too) and any reach up to the one gathered for; a centre beyond
    // the slack, a larger reach or another mesh gathers again. Over a flat floor, a
    // terrace, a floor with a raised vertex and a finely cut cube from both sides.
    let meshes = flat_patched_meshes();
    let mut rnd = uniform(76);
    for (name, m) in &meshes {
        let (mut contacts, mut kept_answers) = (0, 0);
        for case in 0..2000 {
            let (p, r, tolerance) = sphere_case(name, case, &mut rnd);
            let mut cache = NearCache::default();
            assert_eq!(
                m.touches_near(p, r, tolerance, &mut cache),
                m.touches(p, r, tolerance),
                "{name}: gathered at {p:?}"
            );
            let (at, slack) = (cache.at, cache.slack);
            assert_eq!((at, slack), (p, 1e-3 * r));
            // centres within the slack: inside at random, on its faces, at its corners; a
            // smaller tolerance half the time
            for k in 0..12 {
                let q: [f64; 3] = std::array::from_fn(|c| match k % 3 {
                    0 => at[c] + slack * (2.0 * rnd() - 1.0),
                    1 => at[c] + slack * if rnd() < 0.5 { -1.0 } else { 1.0 },
                    _ => at[c] + slack * if c == k % 3 { 1.0 } else { 2.0 * rnd() - 1.0 },
                });
                if (0..3).any(|c| (q[c] - at[c]).abs() > slack) {
                    continue; // (rounded past the slack's edge)
                }
                let t = if k % 2 == 0 { tolerance } else { tolerance * rnd() };
                let want = m.touches(q, r, t);
                assert_eq!(
                    m.touches_near(q, r, t, &mut cache),
                    want,
                    "{name}: gathered at {p:?}, asked at {q:?}, r {r} tolerance {t}"
                );
                assert_eq!(
                    cache.at, at,
                    "{name}: a centre within the slack and a smaller reach use what is kept"
                );
                kept_answers += 1;
                contacts += want.len();
            }
            // beyond the slack, or a larger reach: gathered again, and still the same touches
            let far = [at[0] + 3.0 * slack, at[1], at[2]];
            assert_eq!(m.touches_near(far, r, tolerance, &mut cache), m.touches(far, r, tolerance));
            assert_eq!(cache.at, far, "{name}: a centre beyond the slack gathers again");
            assert_eq!(
                m.touches_near(far, r, tolerance + r, &mut cache),
                m.touches(far, r, tolerance + r)
            );
            assert_eq!(cache.reach, r + (tolerance + r), "{name}: a larger reach gathers again");
        }
        assert!(contacts > 5000, "{name}: the spheres touch the mesh: {contacts}");
        assert!(kept_answers > 10000, "{name}: the kept triangles answered: {kept_answers}");
    }
    // another mesh's cache is never read
    let (a, b) = (&meshes[0].1, &meshes[1].1);
    let mut cache = NearCache::default();
    let p = [0.7, 0.5, 0.02];
    a.touches_near(p, 0.03, 0.0, &mut cache);
    assert_eq!(b.touches_near(p, 0.03, 0.0, &mut cache), b.touches(p, 0.03, 0.0));
}

#[test]
fn spheres_resting_on_a_floor_of_small_triangles_look_under_their_feet_and_meet_what_the_full_search_meets() {
    // Spheres ten cells wide in resting contact with a floor of 2 × 40² triangles (0.25 % of
    // r in, as a pile's balls lie), still, creeping or sliding, under gravity: their first
    // meeting and touch are those of the search of every triangle, and the first search
    // looks only at the flat nodes its path's feet cross (`Flat::foot_path_near`): fewer
    // triangles than those within its reach of the plane (√(2 r δ) about the foot).
    let floor = sheet(40, 0.025, |_, _| 0.0);
    let m = TriangleMesh::new(floor.0, floor.1, false, Surface::default()).unwrap();
    let mut rnd = uniform(7);
    let mut fewer = 0;
    for case in 0..600 {
        let r = 0.25 * (0.8 + 0.4 * rnd());
        let x = [0.2 + 0.6 * rnd(), 0.2 + 0.6 * rnd(), r * (1.0 - 0.0025 * (0.5 + rnd()))];
        let speed = [0.0, 1e-3, 0.05, 0.5][case % 4];
        let v = [speed * (rnd() - 0.5), speed * (rnd() - 0.5), speed * (rnd() - 0.5)];
        let (a, horizon, margin) = ([0.0, 0.0, -9.81], 1e-3, [None, Some(0.02 * r)][case % 2]);
        let want = m.toi_everywhere(x, v, a, r, horizon, margin);
        assert_eq!(
            m.toi_within(x, v, a, r, horizon, margin),
            want,
            "x {x:?} v {v:?} r {r} margin {margin:?}"
        );
        // the flat nodes each search goes into (the path's box as `toi_within` makes it)
        let end = [0, 1, 2].map(|k| x[k] + (v[k] + 0.5 * a[k] * horizon) * horizon);
        let bulge = 0.125 * 9.81 * horizon * horizon;
        let reach = r + margin.unwrap_or(0.0);
        let eps8 = 8.0 * m.eps(x, r);
        let lo = [0, 1, 2].map(|k| x[k].min(end[k]) - reach - bulge);
        let hi = [0, 1, 2].map(|k| x[k].max(end[k]) + reach + bulge);
        let (mut feet, mut path) = (0, 0);
        m.geometry.visit_past_flat(
            lo,
            hi,
            |f| f.holds_foot(x, reach, eps8) || f.foot_path_near((x, end), bulge, eps8),
            |_| feet += 1,
        );
        m.geometry.visit_past_flat(
            lo,
            hi,
            |f| f.holds_foot(x, reach, eps8) || f.near_path((x, end), bulge, r, eps8),
            |_| path += 1,
        );
        assert!(
            feet <= path,
            "the feet's search goes into the nodes of the path's: {feet} > {path}"
        );
        fewer += (feet < path) as usize;
    }
    assert!(
        fewer > 300,
        "the feet's search leaves out triangles within reach: {fewer} of 600"
    );
}

#[test]
fn continuous_detection_past_the_flat_nodes_meets_what_the_full_search_meets() {
    // Spheres on random parabolas (resting, sliding, falling, rising, thrown sideways) over a
    // floor, a terrace and a finely cut cube: the first triangle met and its time, and
    // whether the sphere is within the margin now, are those of the search of every triangle.
    let floor = sheet(40, 0.025, |_, _| 0.0);
    let terrace = sheet(40, 0.025, |i, _| if i > 20 { 0.1 } else { 0.0 });
    let cube = fine_cube(24);
    let meshes = [
        (
            "floor",
            TriangleMesh::new(floor.0, floor.1, false, Surface::default()).unwrap(),
        ),
        (
            "terrace",
            TriangleMesh::new(terrace.0, terrace.1, false, Surface::default()).unwrap(),
        ),
        (
            "cube inside",
            TriangleMesh::new(cube.0, cube.1, true, Surface::default()).unwrap(),
        ),
    ];
    let mut rnd = uniform(29);
    for (name, m) in &meshes {
        let (mut met, mut touching) = (0, 0);
        for case in 0..2500 {
            let cell = 1.0 / 40.0;
            let r = cell * [0.3, 1.0, 2.5][case % 3] * (0.5 + rnd());
            let mut x = [0.05 + 0.9 * rnd(), 0.05 + 0.9 * rnd(), 0.05 + 0.9 * rnd()];
            if !name.starts_with("cube") {
                x[2] = [0.0, 0.1][(x[0] > 0.5 && *name == "terrace") as usize] + r * (0.9 + 0.3 * rnd());
            } else {
                // near a wall of the cube, from inside
                let near = r * (0.9 + 0.3 * rnd());
                x[case % 3] = if rnd() < 0.5 { near } else { 1.0 - near };
            }
            let speed = [0.0, 0.05, 1.0, 5.0][case % 4];
            let v = [speed * (rnd() - 0.5), speed * (rnd() - 0.5), speed * (rnd() - 0.6)];
            let a = [0.0, 0.0, -9.81 * (case % 2) as f64];
            let horizon = [1e-3, 1e-2][case % 2];
            let margin = [None, Some(0.0), Some(0.1 * r)][case % 3];
            let got = m.toi_within(x, v, a, r, horizon, margin);
            let want = m.toi_everywhere(x, v, a, r, horizon, margin);
            assert_eq!(
                got, want,
                "{name}: x {x:?} v {v:?} a {a:?} r {r} horizon {horizon} margin {margin:?}"
            );
            met += want.1.is_some() as usize;
            touching += want.0 as usize;
        }
        assert!(
            met > 300 && touching > 100,
            "{name}: the paths meet the mesh: {met}, touching {touching}"
        );
    }
}
