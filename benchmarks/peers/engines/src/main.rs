//! pile-peer: benchmarks/piles.py's runs of a pile in Box2D v3 (2D, through `boxdd`) and Jolt
//! (3D, through `rolt`/`joltc-sys`), on the states piles.py builds.
//!
//!     pile-peer JOB.json OUT.json
//!
//! The job (JSON): engine "box2d" (dim 2) or "jolt" (dim 3); positions (N x 3; z ignored in 2D),
//! radii (N), the box lo and hi (dim values each), e, mu, gravity (dim values), dt, steps, last
//! (the steps of the final window), threads (default 1); Box2D: substeps (default 4),
//! contact_hertz, contact_damping_ratio, contact_speed (the push-out velocity cap),
//! restitution_threshold (each left at Box2D's default when absent); Jolt: penetration_slop,
//! min_velocity_for_restitution (Jolt's defaults when absent); wall (the walls' thickness, default
//! 0.5 m).
//!
//! Each particle is a dynamic circle / sphere body of mass 1 kg (density 1 / area or 1 / volume,
//! then in Box2D the mass data set to exactly 1 kg) that does not rotate (Box2D: motion lock of
//! the rotation and rotational inertia 0, i.e. inverse inertia 0; Jolt: allowed DOFs the three
//! translations, inverse inertia 0), friction mu and restitution e, no damping. The box: a static floor and walls (no lid) as slabs `wall` thick, friction mu and
//! restitution e. Both engines mix a pair's values as kinema does: restitution max(e_a, e_b),
//! friction sqrt(mu_a mu_b) (Box2D v3: b2DefaultRestitutionCallback / b2DefaultFrictionCallback
//! in physics_world.c; Jolt: ContactConstraintManager's mCombineRestitution / mCombineFriction).
//!
//! The result (JSON): positions at steps - last ("before") and at the end ("x"), the final
//! velocities ("v"), the CPU seconds (getrusage, user + system of the process, all threads) and
//! wall seconds of the step loop alone, the seconds to build, the bodies asleep at the end, the
//! bodies' masses, the largest angular speed, and the engine's settings as used.
use std::ffi::c_void;
use std::time::Instant;

use serde::{Deserialize, Serialize};
use serde_json::{json, Value};

#[derive(Deserialize)]
struct Job {
    engine: String,
    dim: usize,
    positions: Vec<[f64; 3]>,
    radii: Vec<f64>,
    lo: Vec<f64>,
    hi: Vec<f64>,
    e: f64,
    mu: f64,
    gravity: Vec<f64>,
    dt: f64,
    steps: usize,
    last: usize,
    #[serde(default = "one")]
    threads: usize,
    #[serde(default = "half")]
    wall: f64,
    // Box2D
    #[serde(default = "four")]
    substeps: i32,
    contact_hertz: Option<f64>,
    contact_damping_ratio: Option<f64>,
    contact_speed: Option<f64>,
    restitution_threshold: Option<f64>,
    // Jolt
    penetration_slop: Option<f64>,
    min_velocity_for_restitution: Option<f64>,
}

fn one() -> usize {
    1
}
fn half() -> f64 {
    0.5
}
fn four() -> i32 {
    4
}

#[derive(Serialize)]
struct Output {
    engine: String,
    library: String,
    n: usize,
    build: f64,
    cpu: f64,
    wall: f64,
    before: Vec<[f64; 3]>,
    x: Vec<[f64; 3]>,
    v: Vec<[f64; 3]>,
    asleep: usize,
    mass_min: f64,
    mass_max: f64,
    max_omega: f64,
    settings: Value,
    warnings: Vec<String>,
}

/// One engine's world, as the run loop sees it.
trait Pile {
    fn step(&mut self);
    /// positions and velocities, N x 3 (z = 0 in 2D)
    fn state(&mut self) -> (Vec<[f64; 3]>, Vec<[f64; 3]>);
    fn asleep(&mut self) -> usize;
    fn max_omega(&mut self) -> f64;
    fn masses(&mut self) -> Vec<f64>;
    fn settings(&self) -> Value;
    fn warnings(&self) -> Vec<String> {
        Vec::new()
    }
}

/// CPU seconds of this process so far (user + system, all threads).
fn cpu_seconds() -> f64 {
    let mut u: libc::rusage = unsafe { std::mem::zeroed() };
    unsafe { libc::getrusage(libc::RUSAGE_SELF, &mut u) };
    let t = |tv: libc::timeval| tv.tv_sec as f64 + tv.tv_usec as f64 * 1e-6;
    t(u.ru_utime) + t(u.ru_stime)
}

// -- Box2D v3 ------------------------------------------------------------------------------------
mod box2d {
    use super::*;
    use boxdd::{
        shapes, BodyBuilder, BodyId, BodyType, Foundation, MassData, MotionLocks, Position, ShapeDef, SurfaceMaterial, Vec2,
        WorkerCount, World, WorldBuilder,
    };

    pub struct Box2d {
        world: World,
        bodies: Vec<BodyId>,
        dt: f32,
        substeps: i32,
        settings: Value,
    }

    fn err(e: impl std::fmt::Display) -> String {
        format!("box2d: {e}")
    }

    pub fn build(job: &Job) -> Result<Box2d, String> {
        let foundation = Foundation::initialize_default().map_err(err)?;
        let defaults = foundation.world_def();
        let mut wb = WorldBuilder::from(foundation.world_def())
            .gravity(Vec2::new(job.gravity[0] as f32, job.gravity[1] as f32))
            .worker_count(WorkerCount::new(job.threads as u32).map_err(err)?);
        if let Some(h) = job.contact_hertz {
            wb = wb.contact_hertz(h as f32);
        }
        if let Some(z) = job.contact_damping_ratio {
            wb = wb.contact_damping_ratio(z as f32);
        }
        if let Some(s) = job.contact_speed {
            wb = wb.contact_speed(s as f32);
        }
        if let Some(t) = job.restitution_threshold {
            wb = wb.restitution_threshold(t as f32);
        }
        let def = wb.build().map_err(err)?;
        let hertz = def.contact_hertz();
        let inv_h = job.substeps as f32 / job.dt as f32;
        let settings = json!({
            "dt": job.dt,
            "substeps": job.substeps,
            "contact_hertz": hertz,
            // physics_world.c: "Hertz values get reduced for large time steps"
            "contact_hertz_effective": hertz.min(0.125 * inv_h),
            "contact_damping_ratio": def.contact_damping_ratio(),
            "contact_speed": def.contact_speed(),
            "restitution_threshold": def.restitution_threshold(),
            "sleep": def.is_sleep_enabled(),
            "continuous": def.is_continuous_enabled(),
            "defaults": {
                "contact_hertz": defaults.contact_hertz(),
                "contact_damping_ratio": defaults.contact_damping_ratio(),
                "contact_speed": defaults.contact_speed(),
                "restitution_threshold": defaults.restitution_threshold(),
            },
            "threads": job.threads,
        });
        let mut world = foundation.create_world(def).map_err(err)?;

        let material = SurfaceMaterial::new()
            .with_friction(job.mu as f32)
            .map_err(err)?
            .with_restitution(job.e as f32)
            .map_err(err)?;
        // the box: static slabs `wall` thick below the floor and beyond the side walls
        let (x0, y0, x1, y1) = (job.lo[0], job.lo[1], job.hi[0], job.hi[1]);
        let t = job.wall;
        let (cx, h) = ((x0 + x1) / 2.0, y1 - y0);
        let slabs = [
            (cx, y0 - t, (x1 - x0) / 2.0 + t, t),
            (x0 - t, y0 + h / 2.0, t, h / 2.0 + t),
            (x1 + t, y0 + h / 2.0, t, h / 2.0 + t),
        ];
        let wall_def = ShapeDef::builder().material(material).density(0.0).build().map_err(err)?;
        for (px, py, hx, hy) in slabs {
            let body = world
                .create_body(
                    BodyBuilder::from(foundation.body_def())
                        .body_type(BodyType::Static)
                        .position(Position::new(px as f32, py as f32))
                        .build()
                        .map_err(err)?,
                )
                .map_err(err)?;
            world
                .body(body)
                .map_err(err)?
                .create_polygon(&wall_def, &shapes::box_polygon(hx as f32, hy as f32).map_err(err)?)
                .map_err(err)?;
        }
        let mut bodies = Vec::with_capacity(job.radii.len());
        for (p, &r) in job.positions.iter().zip(&job.radii) {
            let r = r as f32;
            let id = world
                .create_body(
                    BodyBuilder::from(foundation.body_def())
                        .body_type(BodyType::Dynamic)
                        .position(Position::new(p[0] as f32, p[1] as f32))
                        .linear_damping(0.0)
                        .angular_damping(0.0)
                        .motion_locks(MotionLocks::new(false, false, true))
                        .build()
                        .map_err(err)?,
                )
                .map_err(err)?;
            let disc_def = ShapeDef::builder()
                .material(material)
                .density(1.0 / (std::f32::consts::PI * r * r))
                .build()
                .map_err(err)?;
            let mut body = world.body(id).map_err(err)?;
            body.create_circle(&disc_def, &shapes::circle(Vec2::new(0.0, 0.0), r).map_err(err)?)
                .map_err(err)?;
            // exactly 1 kg (the density gives it to a rounding), and rotational inertia 0, which
            // Box2D reads as an inverse inertia of 0: the contacts turn nothing (the motion lock
            // alone only zeroes the angular velocity at each substep's integration, solver.c)
            body.set_mass_data(MassData::new(1.0, Vec2::new(0.0, 0.0), 0.0).map_err(err)?)
                .map_err(err)?;
            bodies.push(id);
        }
        Ok(Box2d {
            world,
            bodies,
            dt: job.dt as f32,
            substeps: job.substeps,
            settings,
        })
    }

    impl Pile for Box2d {
        fn step(&mut self) {
            let done = self.world.step(self.dt, self.substeps).expect("box2d step");
            if let Some(e) = done.post_step_error() {
                panic!("box2d step: {e}");
            }
        }
        fn state(&mut self) -> (Vec<[f64; 3]>, Vec<[f64; 3]>) {
            let mut x = Vec::with_capacity(self.bodies.len());
            let mut v = Vec::with_capacity(self.bodies.len());
            for &id in &self.bodies {
                let b = self.world.body(id).expect("box2d body");
                let p = b.position().expect("position");
                let u = b.linear_velocity().expect("velocity");
                x.push([p.x as f64, p.y as f64, 0.0]);
                v.push([u.x as f64, u.y as f64, 0.0]);
            }
            (x, v)
        }
        fn asleep(&mut self) -> usize {
            let mut n = 0;
            for &id in &self.bodies {
                if !self.world.body(id).expect("box2d body").is_awake().expect("awake") {
                    n += 1;
                }
            }
            n
        }
        fn max_omega(&mut self) -> f64 {
            let mut w: f64 = 0.0;
            for &id in &self.bodies {
                w = w.max((self.world.body(id).expect("box2d body").angular_velocity().expect("omega") as f64).abs());
            }
            w
        }
        fn masses(&mut self) -> Vec<f64> {
            let mut m = Vec::with_capacity(self.bodies.len());
            for &id in &self.bodies {
                m.push(self.world.body(id).expect("box2d body").mass().expect("mass") as f64);
            }
            m
        }
        fn settings(&self) -> Value {
            self.settings.clone()
        }
    }
}

// -- Jolt ----------------------------------------------------------------------------------------
mod jolt {
    use super::*;
    use joltc_sys::*;
    use rolt::{
        BodyId, BroadPhaseLayer, BroadPhaseLayerInterface, ObjectLayer, ObjectLayerPairFilter, ObjectVsBroadPhaseLayerFilter,
        PhysicsSystem,
    };
    use std::ptr;

    /// src/jolt_settings.cpp: what JoltC's C API leaves out
    #[repr(C)]
    #[derive(Default, Clone, Copy, Debug)]
    pub struct PileJoltSettings {
        baumgarte: f32,
        speculative_contact_distance: f32,
        penetration_slop: f32,
        linear_cast_threshold: f32,
        max_penetration_distance: f32,
        num_velocity_steps: u32,
        num_position_steps: u32,
        min_velocity_for_restitution: f32,
        time_before_sleep: f32,
        point_velocity_sleep_threshold: f32,
        allow_sleeping: bool,
        gravity: [f32; 3],
    }

    extern "C" {
        fn pile_jolt_get_settings(system: *const c_void, out: *mut PileJoltSettings);
        fn pile_jolt_set_settings(system: *mut c_void, settings: *const PileJoltSettings);
        fn pile_jolt_inverse_mass(body: *const c_void) -> f32;
        fn pile_jolt_inverse_inertia(body: *const c_void, out: *mut f32);
    }

    const OL_STATIC: ObjectLayer = ObjectLayer::new(0);
    const OL_MOVING: ObjectLayer = ObjectLayer::new(1);
    const BPL_STATIC: BroadPhaseLayer = BroadPhaseLayer::new(0);
    const BPL_MOVING: BroadPhaseLayer = BroadPhaseLayer::new(1);

    /// two layers, as in Jolt's HelloWorld: static bodies collide with moving ones only
    struct Layers;

    impl BroadPhaseLayerInterface for Layers {
        fn get_num_broad_phase_layers(&self) -> u32 {
            2
        }
        fn get_broad_phase_layer(&self, layer: ObjectLayer) -> BroadPhaseLayer {
            if layer == OL_STATIC {
                BPL_STATIC
            } else {
                BPL_MOVING
            }
        }
    }

    impl ObjectVsBroadPhaseLayerFilter for Layers {
        fn should_collide(&self, layer: ObjectLayer, bp: BroadPhaseLayer) -> bool {
            layer == OL_MOVING || bp == BPL_MOVING
        }
    }

    impl ObjectLayerPairFilter for Layers {
        fn should_collide(&self, a: ObjectLayer, b: ObjectLayer) -> bool {
            a == OL_MOVING || b == OL_MOVING
        }
    }

    pub struct Jolt {
        system: PhysicsSystem,
        bodies: Vec<BodyId>,
        body_ptrs: Vec<*mut JPC_Body>,
        temp: *mut JPC_TempAllocatorImpl,
        jobs: *mut JPC_JobSystemThreadPool,
        dt: f32,
        settings: Value,
        errors: u32,
    }

    fn rvec3(x: f64, y: f64, z: f64) -> JPC_RVec3 {
        JPC_RVec3 {
            x: x as Real,
            y: y as Real,
            z: z as Real,
            _w: z as Real,
        }
    }

    fn vec3(x: f64, y: f64, z: f64) -> JPC_Vec3 {
        JPC_Vec3 {
            x: x as f32,
            y: y as f32,
            z: z as f32,
            _w: z as f32,
        }
    }

    unsafe fn shape_error(err: *mut JPC_String) -> String {
        std::ffi::CStr::from_ptr(JPC_String_c_str(err)).to_string_lossy().into_owned()
    }

    pub fn build(job: &Job) -> Result<Jolt, String> {
        let n = job.radii.len();
        unsafe {
            rolt::register_default_allocator();
            rolt::factory_init();
            rolt::register_types();
            // room for 10 contacts a ball; the temp allocator holds the step's constraint buffer
            // (PrepareConstraintBuffer: a few hundred bytes a contact) and aborts when full
            let (pairs, contacts) = ((65_536).max(16 * n), (10_240).max(10 * n));
            let temp = JPC_TempAllocatorImpl_new(((32usize << 20) + 1024 * contacts) as _);
            // Jolt's job system: the calling thread works too, so `threads` - 1 more
            let jobs = JPC_JobSystemThreadPool_new3(
                JPC_MAX_PHYSICS_JOBS as _,
                JPC_MAX_PHYSICS_BARRIERS as _,
                job.threads.saturating_sub(1) as _,
            );
            let mut physics = PhysicsSystem::new();
            physics.init((n + 16) as u32, 0, pairs as u32, contacts as u32, Layers, Layers, Layers);
            let system = physics.as_raw();

            // Jolt's defaults as read back (a check that jolt_settings.cpp sees the layout of
            // the PhysicsSystem that joltc-sys built), then the job's settings
            let mut d = PileJoltSettings::default();
            pile_jolt_get_settings(system as *const c_void, &mut d);
            let expect = (
                0.2f32,
                0.02f32,
                0.02f32,
                10u32,
                2u32,
                1.0f32,
                0.5f32,
                0.03f32,
                [0.0f32, -9.81, 0.0],
            );
            let got = (
                d.baumgarte,
                d.speculative_contact_distance,
                d.penetration_slop,
                d.num_velocity_steps,
                d.num_position_steps,
                d.min_velocity_for_restitution,
                d.time_before_sleep,
                d.point_velocity_sleep_threshold,
                d.gravity,
            );
            if got != expect || !d.allow_sleeping {
                return Err(format!(
                    "jolt: the PhysicsSettings read through jolt_settings.cpp are not Jolt 5.0.0's defaults ({d:?}): \
                     its build does not match joltc-sys's build of Jolt"
                ));
            }
            let mut s = d;
            if let Some(slop) = job.penetration_slop {
                s.penetration_slop = slop as f32;
            }
            if let Some(v) = job.min_velocity_for_restitution {
                s.min_velocity_for_restitution = v as f32;
            }
            s.gravity = [job.gravity[0] as f32, job.gravity[1] as f32, job.gravity[2] as f32];
            pile_jolt_set_settings(system as *mut c_void, &s);
            let mut check = PileJoltSettings::default();
            pile_jolt_get_settings(system as *const c_void, &mut check);
            let settings = json!({
                "dt": job.dt,
                "collision_steps": 1,
                "penetration_slop": check.penetration_slop,
                "speculative_contact_distance": check.speculative_contact_distance,
                "baumgarte": check.baumgarte,
                "num_velocity_steps": check.num_velocity_steps,
                "num_position_steps": check.num_position_steps,
                "min_velocity_for_restitution": check.min_velocity_for_restitution,
                "time_before_sleep": check.time_before_sleep,
                "point_velocity_sleep_threshold": check.point_velocity_sleep_threshold,
                "allow_sleeping": check.allow_sleeping,
                "gravity": check.gravity,
                "defaults": {"penetration_slop": d.penetration_slop, "min_velocity_for_restitution": d.min_velocity_for_restitution},
                "threads": job.threads,
            });

            let bi = physics.body_interface().as_raw();
            // the box: static slabs `wall` thick under the floor and beyond the four walls
            let (lo, hi, t) = (&job.lo, &job.hi, job.wall);
            let (cx, cy, h) = ((lo[0] + hi[0]) / 2.0, (lo[1] + hi[1]) / 2.0, hi[2] - lo[2]);
            let (ax, ay) = ((hi[0] - lo[0]) / 2.0 + t, (hi[1] - lo[1]) / 2.0 + t);
            let slabs = [
                ([cx, cy, lo[2] - t], [ax, ay, t]),
                ([lo[0] - t, cy, lo[2] + h / 2.0], [t, ay, h / 2.0]),
                ([hi[0] + t, cy, lo[2] + h / 2.0], [t, ay, h / 2.0]),
                ([cx, lo[1] - t, lo[2] + h / 2.0], [ax, t, h / 2.0]),
                ([cx, hi[1] + t, lo[2] + h / 2.0], [ax, t, h / 2.0]),
            ];
            for (at, half) in slabs {
                let mut shape: *mut JPC_Shape = ptr::null_mut();
                let mut e: *mut JPC_String = ptr::null_mut();
                let ss = JPC_BoxShapeSettings {
                    HalfExtent: vec3(half[0], half[1], half[2]),
                    ..Default::default()
                };
                if !JPC_BoxShapeSettings_Create(&ss, &mut shape, &mut e) {
                    return Err(format!("jolt: box shape: {}", shape_error(e)));
                }
                let bs = JPC_BodyCreationSettings {
                    Position: rvec3(at[0], at[1], at[2]),
                    MotionType: JPC_MOTION_TYPE_STATIC,
                    ObjectLayer: OL_STATIC.raw(),
                    Friction: job.mu as f32,
                    Restitution: job.e as f32,
                    Shape: shape,
                    ..Default::default()
                };
                let body = JPC_BodyInterface_CreateBody(bi, &bs);
                if body.is_null() {
                    return Err("jolt: could not create a wall".into());
                }
                JPC_BodyInterface_AddBody(bi, JPC_Body_GetID(body), JPC_ACTIVATION_DONT_ACTIVATE);
            }
            let mut bodies = Vec::with_capacity(n);
            let mut body_ptrs = Vec::with_capacity(n);
            for (p, &r) in job.positions.iter().zip(&job.radii) {
                let mut shape: *mut JPC_Shape = ptr::null_mut();
                let mut e: *mut JPC_String = ptr::null_mut();
                let r32 = r as f32;
                let ss = JPC_SphereShapeSettings {
                    Radius: r32,
                    // 1 kg: SphereShape::GetMassProperties is 4/3 pi r^3 density
                    Density: 1.0 / (4.0 / 3.0 * std::f32::consts::PI * r32 * r32 * r32),
                    ..Default::default()
                };
                if !JPC_SphereShapeSettings_Create(&ss, &mut shape, &mut e) {
                    return Err(format!("jolt: sphere shape: {}", shape_error(e)));
                }
                let bs = JPC_BodyCreationSettings {
                    Position: rvec3(p[0], p[1], p[2]),
                    MotionType: JPC_MOTION_TYPE_DYNAMIC,
                    ObjectLayer: OL_MOVING.raw(),
                    // no rotation: the three translations alone
                    AllowedDOFs: JPC_ALLOWED_DOFS_TRANSLATIONX | JPC_ALLOWED_DOFS_TRANSLATIONY | JPC_ALLOWED_DOFS_TRANSLATIONZ,
                    Friction: job.mu as f32,
                    Restitution: job.e as f32,
                    // Jolt's default damping 0.05 is a drag none of the others has
                    LinearDamping: 0.0,
                    AngularDamping: 0.0,
                    Shape: shape,
                    ..Default::default()
                };
                let body = JPC_BodyInterface_CreateBody(bi, &bs);
                if body.is_null() {
                    return Err("jolt: could not create a ball (too many bodies?)".into());
                }
                let id = BodyId::new(JPC_Body_GetID(body));
                JPC_BodyInterface_AddBody(bi, id.raw(), JPC_ACTIVATION_ACTIVATE);
                bodies.push(id);
                body_ptrs.push(body);
            }
            physics.optimize_broad_phase();
            Ok(Jolt {
                system: physics,
                bodies,
                body_ptrs,
                temp,
                jobs,
                dt: job.dt as f32,
                settings,
                errors: 0,
            })
        }
    }

    impl Pile for Jolt {
        fn step(&mut self) {
            self.errors |= unsafe { JPC_PhysicsSystem_Update(self.system.as_raw(), self.dt, 1, self.temp, self.jobs) };
        }
        fn state(&mut self) -> (Vec<[f64; 3]>, Vec<[f64; 3]>) {
            let bi = self.system.body_interface();
            let mut x = Vec::with_capacity(self.bodies.len());
            let mut v = Vec::with_capacity(self.bodies.len());
            for &id in &self.bodies {
                // a sphere's centre of mass is its centre
                let (p, u) = (bi.center_of_mass_position(id), bi.linear_velocity(id));
                x.push([p.x as f64, p.y as f64, p.z as f64]);
                v.push([u.x as f64, u.y as f64, u.z as f64]);
            }
            (x, v)
        }
        fn asleep(&mut self) -> usize {
            let bi = self.system.body_interface();
            self.bodies.iter().filter(|&&id| !bi.is_active(id)).count()
        }
        fn max_omega(&mut self) -> f64 {
            let bi = self.system.body_interface().as_raw();
            let mut w: f64 = 0.0;
            for &id in &self.bodies {
                let o = unsafe { JPC_BodyInterface_GetAngularVelocity(bi, id.raw()) };
                w = w.max(((o.x * o.x + o.y * o.y + o.z * o.z) as f64).sqrt());
            }
            w
        }
        fn masses(&mut self) -> Vec<f64> {
            self.body_ptrs
                .iter()
                .map(|&b| {
                    let mut ii = [0f32; 3];
                    unsafe { pile_jolt_inverse_inertia(b as *const c_void, ii.as_mut_ptr()) };
                    assert!(ii == [0.0; 3], "jolt: a ball can rotate (inverse inertia {ii:?})");
                    1.0 / unsafe { pile_jolt_inverse_mass(b as *const c_void) } as f64
                })
                .collect()
        }
        fn settings(&self) -> Value {
            self.settings.clone()
        }
        fn warnings(&self) -> Vec<String> {
            let mut w = Vec::new();
            for (bit, what) in [
                (JPC_PHYSICS_UPDATE_ERROR_MANIFOLD_CACHE_FULL, "manifold cache full"),
                (JPC_PHYSICS_UPDATE_ERROR_BODY_PAIR_CACHE_FULL, "body pair cache full"),
                (JPC_PHYSICS_UPDATE_ERROR_CONTACT_CONSTRAINTS_FULL, "contact constraints full"),
            ] {
                if self.errors & bit != 0 {
                    w.push(format!(
                        "jolt: PhysicsSystem::Update reported: {what} (contacts were dropped)"
                    ));
                }
            }
            w
        }
    }
}

fn run(job: &Job) -> Result<Output, String> {
    let n = job.radii.len();
    if job.positions.len() != n || job.lo.len() != job.dim || job.hi.len() != job.dim || job.gravity.len() != job.dim {
        return Err("positions, radii, lo, hi and gravity do not agree with dim".into());
    }
    if job.last > job.steps {
        return Err("last > steps".into());
    }
    let t0 = Instant::now();
    let (mut pile, library): (Box<dyn Pile>, &str) = match (job.engine.as_str(), job.dim) {
        ("box2d", 2) => (Box::new(box2d::build(job)?), "boxdd 0.6.0 (Box2D 3.2.0 at 56edae7)"),
        ("jolt", 3) => (
            Box::new(jolt::build(job)?),
            "rolt 0.3.1 / joltc-sys 0.3.1 (Jolt Physics 5.0.0)",
        ),
        (e, d) => return Err(format!("engine {e:?} in {d}D: box2d is 2D, jolt is 3D")),
    };
    let build = t0.elapsed().as_secs_f64();
    let masses = pile.masses();
    let (mut cpu, mut wall) = (0.0, 0.0);
    let mut timed = |pile: &mut Box<dyn Pile>, steps: usize| {
        let (c0, w0) = (cpu_seconds(), Instant::now());
        for _ in 0..steps {
            pile.step();
        }
        cpu += cpu_seconds() - c0;
        wall += w0.elapsed().as_secs_f64();
    };
    timed(&mut pile, job.steps - job.last);
    let before = pile.state().0;
    timed(&mut pile, job.last);
    let (x, v) = pile.state();
    Ok(Output {
        engine: job.engine.clone(),
        library: library.into(),
        n,
        build,
        cpu,
        wall,
        before,
        x,
        v,
        asleep: pile.asleep(),
        mass_min: masses.iter().cloned().fold(f64::INFINITY, f64::min),
        mass_max: masses.iter().cloned().fold(f64::NEG_INFINITY, f64::max),
        max_omega: pile.max_omega(),
        settings: pile.settings(),
        warnings: pile.warnings(),
    })
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if args.len() != 3 {
        eprintln!("usage: pile-peer JOB.json OUT.json");
        std::process::exit(2);
    }
    let text = std::fs::read_to_string(&args[1]).unwrap_or_else(|e| {
        eprintln!("pile-peer: {}: {e}", args[1]);
        std::process::exit(2)
    });
    let job: Job = serde_json::from_str(&text).unwrap_or_else(|e| {
        eprintln!("pile-peer: the job: {e}");
        std::process::exit(2)
    });
    match run(&job) {
        Ok(out) => std::fs::write(&args[2], serde_json::to_string(&out).unwrap()).unwrap_or_else(|e| {
            eprintln!("pile-peer: {}: {e}", args[2]);
            std::process::exit(1)
        }),
        Err(e) => {
            eprintln!("pile-peer: {e}");
            std::process::exit(1)
        }
    }
}
