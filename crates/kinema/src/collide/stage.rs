//! The collide stage, stages 2–4 of a world step (`World::collide`, `world/collide.rs`, calls
//! it): the collision settings
//! ([`ContactModel`], [`CollisionParams`]) and [`CollideStage`], which holds them with the
//! colliders, the domain, the materials and the books summed over steps, and runs the impulse
//! model's detection and response of `collide/` (`collide/impulse/`) on each step:
//! detect collisions (continuously inside the step, then as contacts at its end), respond by
//! Newton's restitution law, distribute each impulse onto both particles.

pub use crate::collide::books::ColliderBooks;
pub use crate::collide::contact_force::Cohesion;
use crate::collide::contact_force::{
    particle_ratios, Bodies, ContactForce, RollingModel, SpringDashpot, TangentialLaw, TangentialModel,
};
use crate::collide::event_driven::{unsupported_collider, EventDriven};
use crate::collide::groups::{Filter, GroupMasks};
use crate::collide::impulse::end_of_step::overlap_at;
use crate::collide::impulse::impacts::check_travel;
use crate::collide::impulse::{ImpulseModel, StageSetting};
use crate::collide::records::ContactRecord;
use crate::collide::shock::Accuracy;
use crate::collide::spin::Rotation;
use crate::collide::{placement, Collider, Contact, Domain, Material, MaterialTable, Motion, Periodic};
use crate::error::Error;
use crate::interrupt::Interrupt;
use crate::particles::Particles;
use crate::vec3;

pub(crate) use crate::collide::impulse::end_of_step::on_periodic_wall;
pub use crate::collide::impulse::CollisionStats;
pub(crate) use crate::collide::impulse::{CollisionTimes, StepFrame};

/// The largest turn a moving collider may make in one step, rad (about 5.7°). Continuous
/// detection sees a particle's path from the collider placed at the step's end, carried there
/// on the chord of the turn. Measured on closed cubes turning about any axis with 8–27 balls
/// (e 0–1, μ 0–0.5, half-widths 0.4–0.8 m, 150 steps): none lost in 700 cases up to 0.12 rad a
/// step; 3 of 150 lost between 0.15 and 0.2 rad (balls wedged in a corner at thousands of g,
/// frictionless and inelastic), and more from 0.25 rad.
pub const MAX_TURN: f64 = 0.1;

/// The contact model: how a collision changes the motion.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ContactModel {
    /// Newton's restitution law by impulses after integration (stages 2–4), the seed's model.
    Impulse,
    /// A spring–dashpot force while bodies overlap (the DEM way), integrated with the other
    /// forces in stage 1: F_n = k_n δ − m_eff γ_n u_n with γ_n from the requested e by the
    /// damped oscillator's closed form (`collide/penalty.rs`, `damping_ratio`), or given.
    SpringDashpot {
        /// Normal stiffness k_n, N/m (> 0).
        stiffness: f64,
        /// Damping rate γ_n, 1/s (≥ 0), instead of the one the restitution implies.
        damping: Option<f64>,
    },
    /// Hertz's contact of elastic spheres, integrated as the spring–dashpot force is: F_n =
    /// 4/3 E* √R* δ^(3/2) − c_n u_n, c_n = 2 ζ √(k_n m_eff) at the current secant stiffness
    /// k_n = 4/3 E* √(R* δ), ζ from the requested e (LAMMPS's `pair granular hertz/material`
    /// with `damping coeff_restitution`; `collide/contact_force/law.rs`).
    Hertz {
        /// Young's modulus E of the particles (and the colliders), Pa (> 0).
        youngs_modulus: f64,
        /// Poisson's ratio ν, in [0, 0.5). E* = E / (2 (1 − ν²)) between two such bodies.
        poisson_ratio: f64,
        /// Adhesion of the touching bodies (LAMMPS's `dmt` and `jkr`; `None`: none).
        cohesion: Option<Cohesion>,
    },
}

/// LAMMPS's tangential sub-models with history, by name ([`TangentialArgs`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TangentialKind {
    /// `linear_history`: a tangential spring of constant stiffness k_t.
    LinearHistory,
    /// `mindlin`: k_t = 8 G* a, from Hertz's material (model `hertz` only).
    Mindlin,
}

impl TangentialKind {
    /// The names, as the binding and the scene files spell them.
    pub const NAMES: [&'static str; 2] = ["linear_history", "mindlin"];

    /// The kind named `name`.
    pub fn from_name(name: &str) -> Result<Self, Error> {
        match name {
            "linear_history" => Ok(TangentialKind::LinearHistory),
            "mindlin" => Ok(TangentialKind::Mindlin),
            other => Err(Error::invalid(
                "tangential",
                format!("'{other}'"),
                "the tangential model must be 'linear_history' or 'mindlin'",
            )),
        }
    }

    /// Its name.
    pub fn name(&self) -> &'static str {
        match self {
            TangentialKind::LinearHistory => Self::NAMES[0],
            TangentialKind::Mindlin => Self::NAMES[1],
        }
    }
}

/// The tangential part of the force models (`spring_dashpot`, `hertz`) as a caller names it
/// (`collide/contact_force/tangent.rs`): it acts wherever a contact has friction μ > 0, as
/// Coulomb's cone does in the impulse model. Every field `None` takes its default.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct TangentialArgs {
    /// The law. Default: `linear_history` with `spring_dashpot`, `mindlin` with `hertz`.
    pub kind: Option<TangentialKind>,
    /// k_t of `linear_history`, N/m (> 0). Default with `spring_dashpot`: 2/7 k_n (Silbert et
    /// al. 2001, LAMMPS's `gran/hooke/history`); `hertz` with `linear_history` needs it.
    pub stiffness: Option<f64>,
    /// x_γt ≥ 0, the tangential dashpot as a fraction of the normal one. Default 1/2 (LAMMPS's
    /// `gran/hooke/history`: γ_t = γ_n / 2).
    pub damping: Option<f64>,
    /// k_r of rolling resistance, N/m (> 0; with `rolling_friction`). Default: the
    /// contact's k_t.
    pub rolling_stiffness: Option<f64>,
    /// γ_r of rolling resistance, kg/s (≥ 0). Default: the contact's γ_t.
    pub rolling_damping: Option<f64>,
}

impl TangentialArgs {
    /// The tangential damping fraction when none is given.
    pub const DAMPING: f64 = 0.5;

    /// The fields that are set, by name.
    fn named(&self) -> [(&'static str, Option<f64>); 4] {
        [
            ("tangential_stiffness", self.stiffness),
            ("tangential_damping", self.damping),
            ("rolling_stiffness", self.rolling_stiffness),
            ("rolling_damping", self.rolling_damping),
        ]
    }
}

/// The parameters of the contact models as a caller names them; each belongs to its models
/// ([`ContactModel::from_name`]).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ModelArgs {
    /// k_n, N/m (`spring_dashpot`).
    pub stiffness: Option<f64>,
    /// γ_n, 1/s (`spring_dashpot`).
    pub damping: Option<f64>,
    /// E, Pa (`hertz`).
    pub youngs_modulus: Option<f64>,
    /// ν (`hertz`; default [`ContactModel::POISSON_RATIO`]).
    pub poisson_ratio: Option<f64>,
    /// Adhesion (`hertz`).
    pub cohesion: Option<Cohesion>,
}

impl ContactModel {
    /// The models' names, as the binding and the scene files spell them, in the order an
    /// error lists them.
    pub const NAMES: [&'static str; 3] = ["impulse", "spring_dashpot", "hertz"];

    /// Poisson's ratio of Hertz's model when none is given (glass, steel and most rocks lie
    /// within 0.2–0.3).
    pub const POISSON_RATIO: f64 = 0.3;

    /// E* = E / (2 (1 − ν²)) of Hertz's model between two of its bodies, Pa (Johnson:
    /// 1/E* = (1 − ν_i²)/E_i + (1 − ν_j²)/E_j); `None` for the other models.
    pub fn effective_modulus(&self) -> Option<f64> {
        match *self {
            ContactModel::Hertz {
                youngs_modulus,
                poisson_ratio,
                ..
            } => Some(youngs_modulus / (2.0 * (1.0 - poisson_ratio * poisson_ratio))),
            _ => None,
        }
    }

    /// The model named `name` with its parameters. Each parameter belongs to its models:
    /// giving it to another is an error, and `"spring_dashpot"` needs its stiffness,
    /// `"hertz"` its Young's modulus. (The values themselves are checked by
    /// [`CollisionParams::check`].)
    pub fn from_name(name: &str, args: ModelArgs) -> Result<ContactModel, Error> {
        let ModelArgs {
            stiffness,
            damping,
            youngs_modulus,
            poisson_ratio,
            cohesion,
        } = args;
        let only = |params: &[(&str, Option<f64>)], owner: &str| -> Result<(), Error> {
            match params.iter().find(|p| p.1.is_some()) {
                Some((param, v)) => Err(Error::invalid(
                    *param,
                    v.unwrap_or(f64::NAN),
                    format!("only model={owner} uses it; model='{name}' does not"),
                )),
                None => Ok(()),
            }
        };
        let spring = [("stiffness", stiffness), ("damping", damping)];
        let hertz = [
            ("youngs_modulus", youngs_modulus),
            ("poisson_ratio", poisson_ratio),
            ("surface_energy", cohesion.map(|c| c.surface_energy())),
        ];
        match name {
            "impulse" => {
                only(&spring, "'spring_dashpot'")?;
                only(&hertz, "'hertz'")?;
                Ok(ContactModel::Impulse)
            }
            "spring_dashpot" => {
                only(&hertz, "'hertz'")?;
                match stiffness {
                    Some(stiffness) => Ok(ContactModel::SpringDashpot { stiffness, damping }),
                    None => Err(Error::invalid(
                        "stiffness",
                        "None",
                        "model='spring_dashpot' needs the contact stiffness k_n, finite and > 0 N/m",
                    )),
                }
            }
            "hertz" => {
                only(&[("stiffness", stiffness)], "'spring_dashpot'")?;
                if let Some(g) = damping {
                    return Err(Error::invalid(
                        "damping",
                        g,
                        "model='hertz' takes its damping from the restitution e (LAMMPS's coeff_restitution), not a rate",
                    ));
                }
                match youngs_modulus {
                    Some(youngs_modulus) => Ok(ContactModel::Hertz {
                        youngs_modulus,
                        poisson_ratio: poisson_ratio.unwrap_or(Self::POISSON_RATIO),
                        cohesion,
                    }),
                    None => Err(Error::invalid(
                        "youngs_modulus",
                        "None",
                        "model='hertz' needs the particles' Young's modulus E, finite and > 0 Pa",
                    )),
                }
            }
            other => Err(Error::invalid(
                "model",
                format!("'{other}'"),
                format!(
                    "the contact model must be one of {}",
                    Self::NAMES.map(|n| format!("'{n}'")).join(", ")
                ),
            )),
        }
    }

    /// The model's name ([`ContactModel::NAMES`]) with its parameters: what
    /// [`ContactModel::from_name`] takes back.
    pub fn named(&self) -> (&'static str, ModelArgs) {
        match *self {
            ContactModel::Impulse => (Self::NAMES[0], ModelArgs::default()),
            ContactModel::SpringDashpot { stiffness, damping } => (
                Self::NAMES[1],
                ModelArgs {
                    stiffness: Some(stiffness),
                    damping,
                    ..ModelArgs::default()
                },
            ),
            ContactModel::Hertz {
                youngs_modulus,
                poisson_ratio,
                cohesion,
            } => (
                Self::NAMES[2],
                ModelArgs {
                    youngs_modulus: Some(youngs_modulus),
                    poisson_ratio: Some(poisson_ratio),
                    cohesion,
                    ..ModelArgs::default()
                },
            ),
        }
    }
}

/// The default time to sleep, s: how long an island's particles must all be calm before it
/// sleeps (Box2D's `b2_timeToSleep`).
pub const SLEEP_TIME: f64 = 0.5;

/// How collisions between particles, and with colliders, are handled. Units SI.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CollisionParams {
    /// The contact model. Default [`ContactModel::Impulse`].
    pub model: ContactModel,
    /// Coefficient of restitution e ∈ [0, 1] of every particle without its own (1: elastic,
    /// 0: plastic). Default 1.
    pub restitution: f64,
    /// Coulomb friction coefficient μ ≥ 0 of every particle without its own. Default 0.
    pub friction: f64,
    /// Continuous detection: impacts are found at their time inside the step and resolved
    /// in time order, so nothing passes through a particle or a wall however fast. Default
    /// true.
    pub ccd: bool,
    /// Approach speeds below this use e = 0, m/s, so that resting contacts do not bounce in
    /// place. `None` (default): twice the largest speed change the forces gave a particle in
    /// the step (a body resting under gravity approaches at g·dt each step).
    pub restitution_threshold: Option<f64>,
    /// Sleeping (`collide/sleep.rs`): an island of resting contacts on a collider whose
    /// particles have all been calm this long, s, sleeps until something reaches it. `None`
    /// (or +∞, which the settings read back as `None`): nothing sleeps. Default 0.5 s
    /// (Box2D's time to sleep).
    pub sleep_time: Option<f64>,
    /// The speed below which a particle is calm, m/s. `None` (default): the largest speed
    /// change the forces gave a particle in the step (g·dt under gravity; Chipmunk's rule).
    pub sleep_speed: Option<f64>,
    /// Event-driven dynamics (`collide/event_driven/`): with the impulse model and no forces,
    /// the world jumps from impact to impact between frames instead of stepping, each impact
    /// at its exact time, by the same rule. Needs still planes and boxes as the only
    /// colliders. Default false (stepped).
    pub event_driven: bool,
    /// Rolling resistance μ_r ≥ 0 (dimensionless) in a world with spin: the end-of-step
    /// contacts resist the relative turning of the two bodies across their normal with a
    /// torque of at most μ_r R* F_n (`collide/soft_step.rs`). Default 0. With the force
    /// models, LAMMPS's `rolling sds` and `twisting marshall` (`tangent.rs`).
    pub rolling_friction: f64,
    /// The tangential part of the force models (ignored by the impulse model, which refuses
    /// it set).
    pub tangential: TangentialArgs,
    /// The impulse model's accuracy setting ([`Accuracy`]). Default `Physics`; the force
    /// models and event-driven dynamics refuse `Animation` (they have no end-of-step solve).
    pub accuracy: Accuracy,
    /// Whether particles collide with each other at all (`collide/groups.rs`): false, no
    /// particle pair collides, whatever the groups' matrix says, while every particle still
    /// collides with the colliders (Blender's particles). Default true.
    pub self_collisions: bool,
}

impl Default for CollisionParams {
    fn default() -> Self {
        CollisionParams {
            model: ContactModel::Impulse,
            restitution: 1.0,
            friction: 0.0,
            ccd: true,
            restitution_threshold: None,
            sleep_time: Some(SLEEP_TIME),
            sleep_speed: None,
            event_driven: false,
            rolling_friction: 0.0,
            tangential: TangentialArgs::default(),
            accuracy: Accuracy::Physics,
            self_collisions: true,
        }
    }
}

impl CollisionParams {
    /// The same settings with an infinite time to sleep written as `None` (nothing sleeps).
    fn normalised(self) -> Self {
        CollisionParams {
            sleep_time: self.sleep_time.filter(|t| t.is_finite()),
            ..self
        }
    }

    /// Checks the values; the error names the parameter.
    pub fn check(&self) -> Result<Material, Error> {
        if let ContactModel::SpringDashpot { stiffness, damping } = self.model {
            if !(stiffness.is_finite() && stiffness > 0.0) {
                return Err(Error::invalid(
                    "stiffness",
                    stiffness,
                    "the contact stiffness must be finite and > 0 N/m",
                ));
            }
            if let Some(g) = damping {
                if !(g.is_finite() && g >= 0.0) {
                    return Err(Error::invalid(
                        "damping",
                        g,
                        "the contact damping rate must be finite and >= 0 1/s",
                    ));
                }
            }
        }
        if let ContactModel::Hertz {
            youngs_modulus,
            poisson_ratio,
            cohesion,
        } = self.model
        {
            if let Some(c) = cohesion {
                let gamma = c.surface_energy();
                if !(gamma.is_finite() && gamma >= 0.0) {
                    return Err(Error::invalid(
                        "surface_energy",
                        gamma,
                        format!(
                            "the surface energy γ of {} adhesion must be finite and >= 0 J/m²",
                            c.name().to_uppercase()
                        ),
                    ));
                }
            }
            if !(youngs_modulus.is_finite() && youngs_modulus > 0.0) {
                return Err(Error::invalid(
                    "youngs_modulus",
                    youngs_modulus,
                    "Young's modulus must be finite and > 0 Pa",
                ));
            }
            if !(0.0..0.5).contains(&poisson_ratio) {
                return Err(Error::invalid(
                    "poisson_ratio",
                    poisson_ratio,
                    "Poisson's ratio must be in [0, 0.5) (0.5: incompressible, no Hertz contact)",
                ));
            }
        }
        let t = self.tangential;
        if self.model == ContactModel::Impulse {
            let named = t.named();
            if let Some((param, v)) = named.iter().find(|p| p.1.is_some()) {
                return Err(Error::invalid(
                    *param,
                    v.unwrap_or(f64::NAN),
                    "only the force models ('spring_dashpot', 'hertz') use it; the impulse model's friction is Coulomb's cone",
                ));
            }
            if let Some(k) = t.kind {
                return Err(Error::invalid(
                    "tangential",
                    format!("'{}'", k.name()),
                    "only the force models ('spring_dashpot', 'hertz') use it; the impulse model's friction is Coulomb's cone",
                ));
            }
        }
        for (param, value, what, zero) in [
            ("tangential_stiffness", t.stiffness, "finite and > 0 N/m", false),
            (
                "tangential_damping",
                t.damping,
                "finite and >= 0 (a fraction of the normal dashpot)",
                true,
            ),
            ("rolling_stiffness", t.rolling_stiffness, "finite and > 0 N/m", false),
            ("rolling_damping", t.rolling_damping, "finite and >= 0 kg/s", true),
        ] {
            if let Some(v) = value {
                if !(v.is_finite() && (v > 0.0 || (zero && v == 0.0))) {
                    return Err(Error::invalid(param, v, format!("it must be {what}")));
                }
            }
        }
        match (self.model, t.kind) {
            (ContactModel::SpringDashpot { .. }, Some(TangentialKind::Mindlin)) => {
                return Err(Error::invalid(
                    "tangential",
                    "'mindlin'",
                    "Mindlin's tangential stiffness 8 G* a needs Hertz's material: model='hertz' (or tangential='linear_history')",
                ))
            }
            (ContactModel::Hertz { .. }, Some(TangentialKind::Mindlin) | None) if t.stiffness.is_some() => {
                return Err(Error::invalid(
                    "tangential_stiffness",
                    t.stiffness.unwrap_or(f64::NAN),
                    "Mindlin's tangential stiffness is 8 G* a from Young's modulus and Poisson's ratio; a constant k_t belongs to tangential='linear_history'",
                ))
            }
            (ContactModel::Hertz { .. }, Some(TangentialKind::LinearHistory)) if t.stiffness.is_none() => {
                return Err(Error::invalid(
                    "tangential_stiffness",
                    "None",
                    "model='hertz' with tangential='linear_history' needs the tangential stiffness k_t, finite and > 0 N/m",
                ))
            }
            _ => {}
        }
        if self.accuracy == Accuracy::Animation && (self.model != ContactModel::Impulse || self.event_driven) {
            return Err(Error::invalid(
                "accuracy",
                "'animation'",
                "only the stepped impulse model has an end-of-step solve to set; the force models and event-driven dynamics take 'physics'",
            ));
        }
        if !(self.rolling_friction.is_finite() && self.rolling_friction >= 0.0) {
            return Err(Error::invalid(
                "rolling_friction",
                self.rolling_friction,
                "the rolling resistance coefficient must be finite and >= 0",
            ));
        }
        if let Some(t) = self.restitution_threshold {
            if !(t.is_finite() && t >= 0.0) {
                return Err(Error::invalid(
                    "restitution_threshold",
                    t,
                    "the restitution threshold must be finite and >= 0 m/s (or None for automatic)",
                ));
            }
        }
        for (name, value, what) in [
            (
                "sleep_time",
                self.sleep_time,
                "the time to sleep must be > 0 s (inf or None: nothing sleeps)",
            ),
            (
                "sleep_speed",
                self.sleep_speed,
                "the sleep speed must be finite and > 0 m/s (or None for automatic)",
            ),
        ] {
            if let Some(t) = value {
                let infinite_time = name == "sleep_time" && t == f64::INFINITY;
                if !((t.is_finite() || infinite_time) && t > 0.0) {
                    return Err(Error::invalid(name, t, what));
                }
            }
        }
        Material::new(self.restitution, self.friction)
    }
}

/// The spring–dashpot model the settings ask for: `Some` with that model.
fn spring_dashpot_of(params: &CollisionParams) -> Option<SpringDashpot> {
    let mut model = match params.model {
        ContactModel::SpringDashpot { stiffness, damping } => SpringDashpot::new(stiffness, damping),
        ContactModel::Hertz { cohesion, .. } => {
            let mut model = SpringDashpot::new(0.0, None);
            model.hertz = params.model.effective_modulus();
            model.cohesion = cohesion.filter(|c| c.surface_energy() > 0.0);
            model
        }
        ContactModel::Impulse => return None,
    };
    model.tangential = tangential_of(params);
    Some(model)
}

/// The tangential part of a force model from the settings (checked), with its defaults
/// ([`TangentialArgs`]).
fn tangential_of(params: &CollisionParams) -> Option<TangentialModel> {
    let t = params.tangential;
    let law = match (params.model, t.kind) {
        (ContactModel::SpringDashpot { stiffness, .. }, _) => TangentialLaw::LinearHistory {
            stiffness: t.stiffness.unwrap_or(2.0 / 7.0 * stiffness),
        },
        (ContactModel::Hertz { .. }, Some(TangentialKind::LinearHistory)) => {
            TangentialLaw::LinearHistory { stiffness: t.stiffness? }
        }
        (
            ContactModel::Hertz {
                youngs_modulus,
                poisson_ratio,
                ..
            },
            _,
        ) => TangentialLaw::Mindlin {
            // G* between two bodies of the material: 1/G* = 2 · 2 (2 − ν)(1 + ν)/E
            shear_modulus: youngs_modulus / (4.0 * (2.0 - poisson_ratio) * (1.0 + poisson_ratio)),
        },
        (ContactModel::Impulse, _) => return None,
    };
    Some(TangentialModel {
        law,
        damping: t.damping.unwrap_or(TangentialArgs::DAMPING),
        rolling: (params.rolling_friction > 0.0).then_some(RollingModel {
            friction: params.rolling_friction,
            stiffness: t.rolling_stiffness,
            damping: t.rolling_damping,
        }),
    })
}

/// The collision stages of a world, with their settings, colliders and books; the impulse
/// model's buffers are its [`ImpulseModel`].
pub(crate) struct CollideStage {
    pub params: CollisionParams,
    material: Material,
    /// Per-particle restitution and friction where set (`None`: the global value); empty
    /// until some particle gets its own (32 B per particle otherwise spent on nothing).
    pub own: Vec<(Option<f64>, Option<f64>)>,
    /// The materials of all particles, built from `own` and the global value when some
    /// particle has its own.
    particle_materials: Option<Vec<Material>>,
    pub colliders: Vec<Collider>,
    pub domain: Domain,
    /// Detection and response of the impulse model, and their buffers.
    pub impulse: ImpulseModel,
    /// The spring–dashpot model's constants and buffers, with that model
    /// ([`CollideStage::contact_force`] lends it out with what it reads).
    pub spring_dashpot: Option<SpringDashpot>,
    /// Whether some particle's own material has friction (the force models' tangential part).
    own_friction: bool,
    /// Each particle's (e, ζ) from `particle_materials`, for the spring–dashpot damping.
    particle_ratios: Option<Vec<(f64, f64)>>,
    pub total: CollisionStats,
    pub last: CollisionStats,
    pub times: CollisionTimes,
    /// Each collider's prescribed motion with the placement it was added in (`None`: it
    /// stays where it was added).
    pub motions: Vec<Option<(Motion, Collider)>>,
    /// What the particles gave each collider over all steps.
    pub collider_books: Vec<ColliderBooks>,
    /// What they gave each collider in the last step (the last call, event-driven).
    pub collider_last: Vec<ColliderBooks>,
    /// The event-driven state between calls (`None`: made afresh at the next), with
    /// `params.event_driven`.
    events: Option<EventDriven>,
    /// Which collision groups collide with which (`collide/groups.rs`; all by default).
    pub group_masks: GroupMasks,
    /// Each collider's mask of the groups it collides with (one per collider, all by default).
    pub collider_masks: Vec<u32>,
}

impl CollideStage {
    pub fn new(params: CollisionParams, dim: usize) -> Result<Self, Error> {
        let material = params.check()?;
        let params = params.normalised();
        Ok(CollideStage {
            params,
            material,
            own: Vec::new(),
            particle_materials: None,
            own_friction: false,
            colliders: Vec::new(),
            domain: Domain::open(dim)?,
            impulse: ImpulseModel::new(),
            spring_dashpot: spring_dashpot_of(&params),
            particle_ratios: None,
            total: CollisionStats::default(),
            last: CollisionStats::default(),
            times: CollisionTimes::default(),
            motions: Vec::new(),
            collider_books: Vec::new(),
            collider_last: Vec::new(),
            events: None,
            group_masks: GroupMasks::default(),
            collider_masks: Vec::new(),
        })
    }

    /// The collision groups' filter for particles in `groups` (`Particles::group`), or `None`
    /// when every pair collides.
    pub fn filter<'a>(&'a self, groups: &'a [u8]) -> Option<Filter<'a>> {
        Filter::of(groups, &self.group_masks, self.params.self_collisions, &self.collider_masks)
    }

    /// Gives collider k a prescribed motion from the placement it was added in (`None`:
    /// back there, still), and places it at time `t` (s).
    pub fn set_motion(&mut self, k: usize, motion: Option<Motion>, t: f64) -> Result<(), Error> {
        let n = self.colliders.len();
        if k >= n {
            return Err(Error::invalid(
                "collider",
                k,
                format!("an index below the number of colliders ({n})"),
            ));
        }
        if let (Some(m), Collider::Box(_)) = (&motion, &self.colliders[k]) {
            if m.rotates() {
                return Err(Error::invalid(
                    "angular_velocity",
                    "a turn",
                    "a box collider stays axis-aligned and can only be translated; a turning container is a closed mesh (inside = true)",
                ));
            }
        }
        self.motions.resize(n, None);
        let rest = match self.motions[k].take() {
            Some((_, rest)) => rest,
            None => self.colliders[k].clone(),
        };
        match motion {
            None => self.colliders[k] = rest,
            Some(m) => {
                let (pose, velocity) = m.at(t);
                let placed = rest.posed(&pose, velocity);
                match placed {
                    Ok(c) => {
                        self.colliders[k] = c;
                        self.motions[k] = Some((m, rest));
                    }
                    Err(e) => {
                        self.motions[k] = None;
                        self.colliders[k] = rest;
                        return Err(e);
                    }
                }
            }
        }
        Ok(())
    }

    /// Places the colliders with a prescribed motion where it has them at the step's end `t1`
    /// (s); returns whether any of them moves within the step from `t0` (a keyframed one
    /// outside its keys rests: [`Motion::moves_within`]).
    pub fn place_colliders(&mut self, t0: f64, t1: f64) -> Result<bool, Error> {
        let mut any = false;
        for (k, m) in self.motions.iter().enumerate() {
            if let Some((motion, rest)) = m {
                let (pose, velocity) = motion.over(t0, t1);
                let turn = vec3::norm(velocity.angular) * (t1 - t0);
                // (a step of dt = MAX_TURN / ω is one, whatever the clock's rounding of t1 − t0)
                if turn > MAX_TURN * (1.0 + 1e-9) {
                    return Err(Error::invalid(
                        format!("collider {k}'s turn in one step"),
                        format!("{turn:.3} rad (from t = {t0} s to t = {t1} s)"),
                        format!(
                            "at most {MAX_TURN} rad a step: continuous detection sweeps a turning collider on the chord of \
                             each step's turn, which lets particles through beyond that; a dt of at most {:.3e} s keeps it within",
                            MAX_TURN / vec3::norm(velocity.angular)
                        ),
                    ));
                }
                self.colliders[k] = rest.posed(&pose, velocity)?;
                any |= motion.moves_within(t0, t1);
            }
        }
        Ok(any)
    }

    /// Whether some collider moves within the step from `t0` to `t1` (s).
    pub fn moves_within(&self, t0: f64, t1: f64) -> bool {
        self.motions.iter().flatten().any(|(m, _)| m.moves_within(t0, t1))
    }

    /// Whether some collider has a prescribed motion.
    pub fn has_motion(&self) -> bool {
        self.motions.iter().any(Option::is_some)
    }

    /// Changes the settings, keeping colliders and buffers.
    pub fn set_params(&mut self, params: CollisionParams) -> Result<(), Error> {
        self.material = params.check()?;
        self.params = params.normalised();
        // the spring–dashpot model's list stays (it lists pairs by geometry alone); its
        // constants are the new ones
        self.spring_dashpot = match (self.spring_dashpot.take(), spring_dashpot_of(&self.params)) {
            (Some(mut kept), Some(new)) => {
                (kept.stiffness, kept.hertz, kept.damping) = (new.stiffness, new.hertz, new.damping);
                if kept.tangential != new.tangential {
                    kept.forget_history();
                }
                kept.tangential = new.tangential;
                Some(kept)
            }
            (_, new) => new,
        };
        self.events = None;
        self.refresh_materials()
    }

    /// Forgets the last step's contacts and figures (a step of the spring–dashpot model).
    pub fn clear_step(&mut self) {
        self.impulse.detected.clear();
        self.last = CollisionStats::default();
        self.collider_last.clear();
    }

    /// A step of the force models (`h`, s): the books its force evaluation kept (velocity
    /// Verlet's fused pass; none with the other methods) as the step's collision figures:
    /// the contacts pushing, those begun in the step as its impacts, the dashpots' power
    /// times h as the energy lost (with what JKR's contacts lost as they let go), h times the
    /// pairs' virial.
    pub fn book_contact_force(&mut self, h: f64) {
        self.clear_step();
        let Some((books, walls)) = self.spring_dashpot.as_ref().and_then(|m| m.take_books()) else {
            return;
        };
        self.book_colliders(walls);
        let step = CollisionStats {
            contacts: books.contacts,
            impacts: books.begun,
            energy_lost: h * books.power + books.lost,
            virial: books.virial.map(|w| h * w),
            ..CollisionStats::default()
        };
        self.last = step;
        self.total.accumulate(&step);
    }

    /// The impulse model's end-of-step contacts of the last step, then those of the islands
    /// asleep (their last awake step's loads), each with its impulse and its mean force over
    /// the step h (s): the impulse's normal part (J·n) n and the rest,
    /// each over h; sliding when the tangential part is at the Coulomb bound μ (J·n) (to
    /// 1e-9 of it). `x` (m, 3 per particle) and `radius` place the points.
    pub fn impulse_reports(&self, x: &[f64], radius: &[f64], h: f64) -> Vec<crate::collide::ContactReport> {
        let table = MaterialTable::uniform(self.material).with_colliders(&self.colliders);
        let materials = match &self.particle_materials {
            Some(m) => table.with_particles(m),
            None => table,
        };
        let asleep = self.impulse.sleeping_contacts(x, radius, &self.colliders, &self.domain);
        self.impulse
            .detected_with_totals()
            .map(|(c, p)| (*c, p))
            .chain(asleep)
            .map(|(c, p)| {
                let c = &c;
                let lambda = vec3::dot(p, c.normal);
                let along = vec3::scale(lambda, c.normal);
                let across = vec3::sub(p, along);
                let cap = materials.pair(c).friction() * lambda;
                let rj = c.partner_particle().map(|j| radius[j]);
                // the point where the contact is now (the overlap as detected was pushed out)
                let now = Contact {
                    overlap: overlap_at(radius, &self.colliders, &self.domain, x, c.i, c.other),
                    ..*c
                };
                crate::collide::ContactReport {
                    contact: *c,
                    point: crate::collide::ContactReport::point_of(&now, vec3::get(x, c.i), radius[c.i], rj),
                    force_n: vec3::scale(1.0 / h, along),
                    force_t: vec3::scale(1.0 / h, across),
                    impulse: [along, across],
                    sliding: cap > 0.0 && vec3::norm(across) >= cap * (1.0 - 1e-9),
                }
            })
            .collect()
    }

    /// The global material and the per-particle ones (if any particle has its own).
    pub fn materials_parts(&self) -> (Material, Option<Vec<Material>>) {
        (self.material, self.particle_materials.clone())
    }

    /// Moves what the stage holds per particle (their own materials: `own`, and the
    /// materials and damping ratios made of them) to a new order of the particles
    /// (`old_of_new[i]`: the index now of the particle that goes to place i), as
    /// [`crate::World`] moves the particles' arrays when it sorts them along space.
    pub fn permute_particles(&mut self, old_of_new: &[u32]) {
        fn gather<T: Copy>(v: &mut Vec<T>, old_of_new: &[u32]) {
            if v.len() == old_of_new.len() {
                *v = old_of_new.iter().map(|&o| v[o as usize]).collect();
            }
        }
        gather(&mut self.own, old_of_new);
        if let Some(m) = &mut self.particle_materials {
            gather(m, old_of_new);
        }
        if let Some(r) = &mut self.particle_ratios {
            gather(r, old_of_new);
        }
    }

    /// Every contact's warm start, the sleeping islands' too (for a checkpoint).
    pub fn all_warm(&self) -> Vec<ContactRecord> {
        self.impulse.all_warm()
    }

    /// Sets the warm start (a checkpoint's), and with it which contacts rested.
    pub fn set_warm_start(&mut self, warm: Vec<ContactRecord>) {
        self.impulse.set_warm_start(warm);
    }

    /// Rebuilds the per-particle materials from `own` and the global value.
    pub fn refresh_materials(&mut self) -> Result<(), Error> {
        if self.own.iter().all(|(e, m)| e.is_none() && m.is_none()) {
            self.particle_materials = None;
            self.particle_ratios = None;
            self.own_friction = false;
            return Ok(());
        }
        let global = self.material;
        self.particle_materials = Some(
            self.own
                .iter()
                .map(|(e, m)| Material::new(e.unwrap_or(global.restitution()), m.unwrap_or(global.friction())))
                .collect::<Result<_, _>>()?,
        );
        self.particle_ratios = self.particle_materials.as_deref().map(particle_ratios);
        self.own_friction = self
            .particle_materials
            .as_deref()
            .is_some_and(|o| o.iter().any(|m| m.friction() > 0.0));
        Ok(())
    }

    /// The spring–dashpot contact force on particles of radii `radius` (m) and inverse masses
    /// `inv_mass` (1/kg), with this stage's materials, colliders and domain, for one call;
    /// `None` with the impulse model.
    pub fn contact_force<'a>(
        &'a self,
        radius: &'a [f64],
        inv_mass: &'a [f64],
        omega: &'a [f64],
        group: &'a [u8],
    ) -> Option<ContactForce<'a>> {
        let model = self.spring_dashpot.as_ref()?;
        let own = self.particle_materials.as_deref().zip(self.particle_ratios.as_deref());
        Some(ContactForce::new(
            model,
            Bodies {
                global: self.material,
                own,
                own_friction: self.own_friction,
                radius,
                inv_mass,
                colliders: &self.colliders,
                domain: &self.domain,
                omega,
                filter: self.filter(group),
            },
        ))
    }

    /// Makes the axes `axes` periodic with the cell [lo, hi) (m); the walls of a box
    /// collider along those axes are removed (particles leaving one side come back on the
    /// other). `None` makes space open again.
    pub fn set_periodic(&mut self, periodic: Option<Periodic>) -> Result<(), Error> {
        let dim = self.domain.dim();
        self.domain = match periodic {
            Some(p) => Domain::periodic(dim, p)?,
            None => Domain::open(dim)?,
        };
        Ok(())
    }

    /// Forgets the candidate list and the warm start (particles, colliders or the domain
    /// changed).
    pub fn forget_list(&mut self) {
        self.impulse.forget_list();
        self.events = None;
    }

    /// Refuses particles `from` on placed where this contact model cannot resolve them
    /// ([`placement::check`], with the impulse model's grid).
    pub fn check_placement(&mut self, p: &Particles, from: usize, user_of: Option<&[u32]>) -> Result<placement::Overlaps, Error> {
        let rule = match self.params.model {
            ContactModel::Impulse => placement::Rule::CentreInside,
            ContactModel::SpringDashpot { .. } | ContactModel::Hertz { .. } => placement::Rule::Coincident,
        };
        let place = placement::Placed {
            x: &p.x,
            radius: &p.radius,
            from,
            user_of,
            filter: Filter::of(&p.group, &self.group_masks, self.params.self_collisions, &self.collider_masks),
        };
        placement::check(&mut self.impulse.grid, &place, &self.domain, &self.colliders, rule)
    }

    /// The impulse model, lent for a step (`World::collide` runs its
    /// [`ImpulseModel::step`]), and what its stages see of the world: these settings,
    /// colliders, domain and materials, and the particles `p`.
    pub fn impulse_and_setting<'a>(&'a mut self, p: &'a Particles) -> (&'a mut ImpulseModel, StageSetting<'a>) {
        let table = MaterialTable::uniform(self.material).with_colliders(&self.colliders);
        let set = StageSetting {
            colliders: &self.colliders,
            domain: &self.domain,
            materials: match &self.particle_materials {
                Some(m) => table.with_particles(m),
                None => table,
            },
            ccd: self.params.ccd,
            restitution_threshold: self.params.restitution_threshold,
            sleep_time: self.params.sleep_time,
            sleep_speed: self.params.sleep_speed,
            radius: &p.radius,
            id: &p.id,
            inv_mass: &p.inv_mass,
            mass: &p.mass,
            rotation: p.has_spin().then_some(Rotation {
                inv_inertia: &p.inv_inertia,
                radius: &p.radius,
            }),
            rolling_friction: self.params.rolling_friction,
            accuracy: self.params.accuracy,
            filter: Filter::of(&p.group, &self.group_masks, self.params.self_collisions, &self.collider_masks),
        };
        (&mut self.impulse, set)
    }

    /// What the particles gave each collider in a step (`step`, one per collider, or fewer:
    /// the rest gave nothing): the last step's, and added to the sums over steps.
    fn book_colliders(&mut self, mut step: Vec<ColliderBooks>) {
        let n = self.colliders.len();
        step.resize(n, ColliderBooks::default());
        self.collider_books.resize(n, ColliderBooks::default());
        for (all, given) in self.collider_books.iter_mut().zip(&step) {
            all.add_scaled(1.0, given);
        }
        self.collider_last = step;
    }

    /// Books what a step of the impulse model did (`stats`) and its time: the sums over
    /// steps, and what the particles gave each collider.
    pub fn book_step(&mut self, stats: CollisionStats, times: CollisionTimes) {
        let step = self.impulse.collider_books.clone();
        self.book_colliders(step);
        self.times.detect += times.detect;
        self.times.respond += times.respond;
        self.times.distribute += times.distribute;
        for (all, step) in self.times.stages.iter_mut().zip(times.stages) {
            *all += step;
        }
        self.last = stats;
        self.total.accumulate(&stats);
    }

    /// Why the event-driven path cannot run on this stage (a sentence), or `None`: it needs
    /// the impulse model, no forces but uniform fields (`other`: the name of a force that is
    /// not one; `field`: their summed acceleration, m/s²), no moving collider, and still
    /// planes and boxes as colliders. Under a field, no particle may be pinned (it would not
    /// fall with the others) and, with walls, every restitution must be 1: a dissipative
    /// bounce on a floor comes to rest through infinitely many ever smaller bounces, which
    /// events cannot run and a resting contact needs the stepped model for.
    pub fn events_refused(&self, other: Option<&str>, field: [f64; 3], p: &Particles) -> Option<String> {
        if self.params.model != ContactModel::Impulse {
            return Some("it is a way of running the impulse model, not the spring–dashpot one".into());
        }
        if let Some(name) = other {
            return Some(format!(
                "particles must fly free between impacts (forces: none or uniform fields such as gravity), and this world has the force '{name}'"
            ));
        }
        if field != [0.0; 3] {
            if let Some(i) = p.inv_mass.iter().position(|&w| w == 0.0) {
                return Some(format!(
                    "particle {i} is pinned, and under a field it would not fall with the others"
                ));
            }
            let walls = self
                .colliders
                .iter()
                .any(|c| matches!(c, Collider::Plane(_) | Collider::Box(_)));
            let global = self.material.restitution() < 1.0;
            let own = self
                .particle_materials
                .as_ref()
                .is_some_and(|m| m.iter().any(|m| m.restitution() < 1.0));
            let surface = self
                .colliders
                .iter()
                .any(|c| c.surface().restitution().is_some_and(|e| e < 1.0));
            if walls && (global || own || surface) {
                return Some(
                    "under a field with walls every restitution must be 1: a dissipative bounce on a floor comes to rest \
                     through ever smaller bounces, a resting contact that only the stepped model holds"
                        .into(),
                );
            }
        }
        if self.has_motion() {
            return Some("a collider moves".into());
        }
        if let Some((k, what)) = unsupported_collider(&self.colliders) {
            return Some(format!("collider {k} is {what}; only planes and boxes are walls to it"));
        }
        None
    }

    /// Runs the particles `p` by events from time `t0` to `t1` (s) under the uniform field
    /// `field` (m/s²) ([`EventDriven::advance`]),
    /// keeping the state for the next call; books the impacts like [`CollideStage::book_step`]. The
    /// caller checked [`CollideStage::events_refused`].
    pub fn advance_events(
        &mut self,
        p: &mut Particles,
        t0: f64,
        t1: f64,
        field: [f64; 3],
        interrupt: &mut Interrupt,
    ) -> Result<(), Error> {
        self.domain.check_radii(&p.radius)?;
        // As a step refuses it (`impulse/impacts.rs`, `check_travel`): a particle that would
        // cross the scene more than TRAVEL_LIMIT times until t1 takes more events than any run
        // can follow (1e10 m/s in a 1 m box: 1e7 wall events a millisecond).
        // (by the largest component, which does not overflow where |v|² would: 1e200 m/s)
        let largest = |a: [f64; 3]| a.iter().fold(0.0_f64, |m, c| m.max(c.abs()));
        let (fastest, speed) =
            (0..p.len())
                .map(|i| (i, largest(vec3::get(&p.v, i))))
                .fold((0, 0.0), |a, b| if b.1 > a.1 || b.1.is_nan() { b } else { a });
        let span = t1 - t0;
        let travel = speed * span + 0.5 * largest(field) * span * span;
        if travel.is_nan() || travel.is_infinite() {
            return Err(Error::Diverged {
                step: 0,
                time: 0.0,
                particle: Some(fastest),
                dt: span,
                reason: crate::error::Divergence::NonFinite,
                advised_dt: None,
                verlet_only: false,
            });
        }
        check_travel(&self.colliders, &p.radius, &p.x, travel, fastest, span)?;
        let start = std::time::Instant::now();
        let mut events = match self.events.take() {
            Some(e) if e.is_at(p.len(), t0, field) => e,
            _ => {
                let filter = Filter::of(&p.group, &self.group_masks, self.params.self_collisions, &self.collider_masks);
                EventDriven::new(p, &self.colliders, &self.domain, filter, t0, field)
            }
        };
        let table = MaterialTable::uniform(self.material).with_colliders(&self.colliders);
        let materials = match &self.particle_materials {
            Some(m) => table.with_particles(m),
            None => table,
        };
        let threshold = self.params.restitution_threshold.unwrap_or(0.0);
        let mut given = vec![ColliderBooks::default(); self.colliders.len()];
        let stats = events.advance(p, &materials, threshold, &self.domain, t1, &mut given, interrupt)?;
        self.book_colliders(given);
        self.events = Some(events);
        self.times.detect += start.elapsed();
        self.last = stats;
        self.total.accumulate(&stats);
        Ok(())
    }
}
