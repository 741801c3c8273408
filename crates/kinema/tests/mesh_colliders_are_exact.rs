//! Triangle-mesh colliders in a World (impulse model, continuous detection) against closed
//! forms and against the analytic colliders they tessellate.
//!
//! Theory used: a ball bouncing on a plane under gravity g along −n (the plane's normal)
//! leaves each impact with the normal speed e times the one it came in with, so its apexes
//! above the plane, u²/2g, fall by e² per bounce; against a fixed body with normal n and
//! e = 1, frictionless, the velocity is reflected, v' = v − 2 (v·n) n, where n is the
//! normal of the feature met (a face's normal, from a convex edge or corner to the centre);
//! an elastic gas's kinetic energy is conserved by every impulse.

mod common;

use kinema::collide::{BoxContainer, Plane, Surface, TriangleMesh};
use kinema::forces::Gravity;
use kinema::ode::Method;
use kinema::world::CollisionParams;
use kinema::World;

fn world(e: f64, dt: f64) -> World {
    let collisions = CollisionParams {
        restitution: e,
        friction: 0.0,
        sleep_time: None,
        ..CollisionParams::default()
    };
    common::impulse_world(3, Method::Verlet, dt, collisions)
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// The unit cube [0, 1]³ scaled by `side`, as 2 triangles per face split `k` × `k`
/// (2 k² triangles a face), wound counter-clockwise from outside.
fn cube(side: f64, k: usize) -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
    let mut v = Vec::new();
    let mut f = Vec::new();
    // each face: an origin corner and two edge directions whose cross product points out
    let faces: [([f64; 3], [f64; 3], [f64; 3]); 6] = [
        ([0.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]), // z = 0, −z
        ([0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]), // z = 1, +z
        ([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]), // y = 0, −y
        ([0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]), // y = 1, +y
        ([0.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, 1.0, 0.0]), // x = 0, −x
        ([1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]), // x = 1, +x
    ];
    for (o, a, b) in faces {
        let base = v.len() as u32;
        for j in 0..=k {
            for i in 0..=k {
                let (s, t) = (i as f64 / k as f64, j as f64 / k as f64);
                v.push([0, 1, 2].map(|c| side * (o[c] + s * a[c] + t * b[c])));
            }
        }
        let row = k as u32 + 1;
        for j in 0..k as u32 {
            for i in 0..k as u32 {
                let p = base + j * row + i;
                f.push([p, p + 1, p + row + 1]);
                f.push([p, p + row + 1, p + row]);
            }
        }
    }
    // the faces share their border vertices by position only: weld them
    let mut welded: Vec<[f64; 3]> = Vec::new();
    let mut index = Vec::with_capacity(v.len());
    for p in &v {
        match welded.iter().position(|q| q == p) {
            Some(k) => index.push(k as u32),
            None => {
                welded.push(*p);
                index.push(welded.len() as u32 - 1);
            }
        }
    }
    let f = f.into_iter().map(|t| t.map(|k| index[k as usize])).collect();
    (welded, f)
}

#[test]
fn a_ball_on_a_tilted_triangle_bounces_as_on_its_plane_with_e_squared_apexes() {
    // A triangle tilted 30° about x, normal n = (0, −sin 30°, cos 30°), far larger than the
    // ball's path; gravity along −n, so that every bounce is along n. The same ball above
    // the triangle's plane (a Plane collider) follows the same trajectory to 1e-12 m; the
    // apexes above the plane, read from the normal speed after each bounce (u²/2g, exact),
    // fall by e² per bounce.
    let (s, c) = (30f64.to_radians().sin(), 30f64.to_radians().cos());
    let n = [0.0, -s, c];
    let (g, e, r) = (9.81, 0.8, 0.1);
    let tri = TriangleMesh::new(
        vec![
            [-50.0, -50.0 * c, -50.0 * s],
            [50.0, -50.0 * c, -50.0 * s],
            [0.0, 50.0 * c, 50.0 * s],
        ],
        vec![[0, 1, 2]],
        false,
        Surface::default(),
    )
    .unwrap();
    let plane = Plane::new([0.0; 3], n, Surface::default()).unwrap();
    let x0 = [0.3, 1.2 * n[1], 1.2 * n[2]];
    let run = |with_mesh: bool| {
        let mut w = world(e, 1e-3);
        w.add_particles(&x0, &[0.2, 0.1, 0.0], &[1.0], &[r], &[false]).unwrap();
        w.add_force(Box::new(Gravity::new(n.map(|k| -g * k)).unwrap())).unwrap();
        if with_mesh {
            w.add_collider(tri.clone()).unwrap();
        } else {
            w.add_collider(plane).unwrap();
        }
        let mut path = Vec::new();
        for _ in 0..4000 {
            w.step().unwrap();
            let p = w.particles();
            path.push(([p.x[0], p.x[1], p.x[2]], [p.v[0], p.v[1], p.v[2]]));
        }
        path
    };
    let (mesh, flat) = (run(true), run(false));
    for (k, ((xm, vm), (xp, vp))) in mesh.iter().zip(&flat).enumerate() {
        for a in 0..3 {
            assert!((xm[a] - xp[a]).abs() < 1e-12, "step {k}: x {xm:?} vs {xp:?}");
            assert!((vm[a] - vp[a]).abs() < 1e-11, "step {k}: v {vm:?} vs {vp:?}");
        }
    }
    // the normal speed right after each bounce: where u_n jumps from − to +
    let mut speeds = Vec::new();
    for w in mesh.windows(2) {
        let (u0, u1) = (dot(w[0].1, n), dot(w[1].1, n));
        if u0 < -0.05 && u1 > 0.0 {
            // u1 = u − g t at a time t after a bounce at speed u; the height above the plane
            // is then h = u t − ½ g t² = u1 t + ½ g t², so t = (√(u1² + 2 g h) − u1) / g
            let h = dot(w[1].0, n) - r;
            let t = ((u1 * u1 + 2.0 * g * h).sqrt() - u1) / g;
            speeds.push(u1 + g * t);
        }
    }
    assert!(speeds.len() >= 5, "bounces: {speeds:?}");
    for pair in speeds.windows(2).take(5) {
        let ratio = (pair[1] / pair[0]).powi(2);
        assert!((ratio - e * e).abs() < 1e-9, "apex ratio {ratio} vs e² {}", e * e);
    }
}

#[test]
fn a_ball_meets_a_convex_edge_and_corner_along_their_own_normal() {
    // e = 1, frictionless, no forces: a ball aimed at the cube's edge x = z = 1 along
    // −(1, 0, 1)/√2 (and with a sliding part along the edge) leaves reflected about that
    // normal; aimed at the corner (1, 1, 1) along −(1, 1, 1)/√3, reflected about it.
    let (v, f) = cube(1.0, 3);
    let r = 0.1;
    let s2 = std::f64::consts::FRAC_1_SQRT_2;
    let s3 = 1.0 / 3f64.sqrt();
    for (n, slide) in [([s2, 0.0, s2], [0.0, 0.7, 0.0]), ([s3, s3, s3], [0.0; 3])] {
        let mesh = TriangleMesh::new(v.clone(), f.clone(), false, Surface::default()).unwrap();
        let mut w = world(1.0, 1e-3);
        let feature = if n[1] == 0.0 { [1.0, 0.5, 1.0] } else { [1.0, 1.0, 1.0] };
        let x0: Vec<f64> = (0..3).map(|k| feature[k] + 0.5 * n[k]).collect();
        let v0: Vec<f64> = (0..3).map(|k| -2.0 * n[k] + slide[k]).collect();
        w.add_particles(&x0, &v0, &[1.0], &[r], &[false]).unwrap();
        w.add_collider(mesh).unwrap();
        for _ in 0..400 {
            w.step().unwrap();
        }
        let p = w.particles();
        let want: Vec<f64> = (0..3).map(|k| 2.0 * n[k] + slide[k]).collect();
        for k in 0..3 {
            assert!((p.v[k] - want[k]).abs() < 1e-12, "n {n:?}: v {:?} vs {want:?}", &p.v[..3]);
        }
        assert_eq!(w.collision_stats().unwrap().1.impacts, 1, "n {n:?}");
    }
}

#[test]
fn a_mesh_box_holds_a_ball_as_the_box_does() {
    // A closed mesh cube as a container (particles inside), 2 × 4 × 4 triangles a face, and
    // a BoxContainer of the same size: a ball under gravity thrown into a corner, with
    // e = 0.9 and friction, follows the same path in both to 1e-12 m over 3 s (its faces,
    // seams and corner give the box's normals).
    let run = |mesh: bool| {
        let collisions = CollisionParams {
            restitution: 0.9,
            friction: 0.3,
            sleep_time: None,
            ..CollisionParams::default()
        };
        let mut w = common::impulse_world(3, Method::Verlet, 1e-3, collisions);
        w.add_particles(&[0.5, 0.4, 0.6], &[2.1, 1.7, 1.3], &[1.0], &[0.05], &[false])
            .unwrap();
        w.add_force(Box::new(Gravity::new([0.0, 0.0, -9.81]).unwrap())).unwrap();
        if mesh {
            let (v, f) = cube(1.0, 4);
            w.add_collider(TriangleMesh::new(v, f, true, Surface::default()).unwrap())
                .unwrap();
        } else {
            w.add_collider(BoxContainer::new([0.0; 3], [1.0; 3], Surface::default()).unwrap())
                .unwrap();
        }
        (0..3000)
            .map(|_| {
                w.step().unwrap();
                w.particles().x[..3].to_vec()
            })
            .collect::<Vec<_>>()
    };
    let (mesh, box_) = (run(true), run(false));
    for (k, (a, b)) in mesh.iter().zip(&box_).enumerate() {
        for c in 0..3 {
            assert!((a[c] - b[c]).abs() < 1e-12, "step {k}: {a:?} vs {b:?}");
        }
    }
}

#[test]
fn an_elastic_gas_in_a_closed_mesh_box_keeps_its_energy() {
    // 343 particles of mixed mass, e = 1, no forces, in a closed mesh cube (2 × 5 × 5
    // triangles a face) as a container: over 2 s (thousands of impacts, with the walls
    // and each other) the kinetic energy stays the same to 1e-12 relative, and no
    // particle leaves the cube.
    let (side, cells, n) = (1.0, 7, 343);
    let (v, f) = cube(side, 5);
    let mut w = world(1.0, 1e-3);
    w.add_collider(TriangleMesh::new(v, f, true, Surface::default()).unwrap())
        .unwrap();
    let spacing = side / cells as f64;
    let mut seed = 2024u64;
    let mut rnd = || {
        seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    };
    let (mut x, mut vel, mut m) = (Vec::new(), Vec::new(), Vec::new());
    for i in 0..n {
        let (a, b, c) = (i % cells, (i / cells) % cells, i / (cells * cells));
        x.extend([a, b, c].map(|q| (q as f64 + 0.5) * spacing));
        vel.extend([rnd(), rnd(), rnd()].map(|u| 4.0 * u));
        m.push(1.0 + (i % 3) as f64);
    }
    let r = 0.03;
    w.add_particles(&x, &vel, &m, &vec![r; n], &vec![false; n]).unwrap();
    let e0 = w.diagnostics().kinetic;
    for _ in 0..2000 {
        w.step().unwrap();
    }
    let e1 = w.diagnostics().kinetic;
    let (_, total) = w.collision_stats().unwrap();
    eprintln!("impacts {}, ΔE/E {:e}", total.impacts, e1 / e0 - 1.0);
    assert!(total.impacts > 5000, "the gas collides: {} impacts", total.impacts);
    assert!((e1 / e0 - 1.0).abs() < 1e-12, "kinetic energy {e0} → {e1}");
    let p = w.particles();
    for (q, c) in p.x.iter().enumerate() {
        assert!(*c >= r - 1e-9 && *c <= side - r + 1e-9, "particle {}: {c}", q / 3);
    }
}
