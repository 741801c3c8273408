//! The collision settings as a caller gives them: the contact model ([`ContactModel`], with
//! its parameters by name, [`ModelArgs`]), the tangential part of the force models
//! ([`TangentialArgs`], [`TangentialKind`]) and [`CollisionParams`] with its checks; and the
//! contact force model they ask for. Units SI.

use crate::collide::contact_force::{
    Cohesion, ContactForceModel, DampingLaw, NormalLaw, RollingLaw, TangentialLaw, TangentialModel, TwistingLaw,
};
use crate::collide::shock::Accuracy;
use crate::collide::Material;
use crate::error::Error;

/// The contact model: how a collision changes the motion.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ContactModel {
    /// Newton's restitution law by impulses after integration (stages 2–4), the seed's model.
    Impulse,
    /// A spring–dashpot force while bodies overlap (the DEM way), integrated with the other
    /// forces in stage 1: F_n = k_n δ − m_eff γ_n u_n with γ_n from the requested e by the
    /// damped oscillator's closed form (`collide/contact_force/spring_dashpot.rs`, `damping_ratio`), or given.
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
    /// The names, as the binding and the scene files spell them (the laws', `tangent.rs`).
    pub const NAMES: [&'static str; 2] = TangentialLaw::NAMES;

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

    /// The force models' names (contacts as a force of stage 1, [`ContactForceModel`]): every
    /// model but the impulse one. Python's rules for them read this list (`_core.FORCE_MODELS`).
    pub const FORCE_MODELS: [&'static str; 2] = [Self::NAMES[1], Self::NAMES[2]];

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
    pub(super) fn normalised(self) -> Self {
        CollisionParams {
            sleep_time: self.sleep_time.filter(|t| t.is_finite()),
            ..self
        }
    }

    /// Checks the values; the error names the parameter.
    pub fn check(&self) -> Result<Material, Error> {
        self.check_model()?;
        self.check_tangential()?;
        self.check_solver()?;
        Material::new(self.restitution, self.friction)
    }

    /// Checks the contact model's own parameters (the spring–dashpot's, Hertz's).
    fn check_model(&self) -> Result<(), Error> {
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
        Ok(())
    }

    /// Checks the tangential part: set only with a force model, each value in its range, the
    /// law's parameters those of its model.
    fn check_tangential(&self) -> Result<(), Error> {
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
        Ok(())
    }

    /// Checks the solver's settings: the accuracy, rolling friction, the restitution
    /// threshold, sleeping.
    fn check_solver(&self) -> Result<(), Error> {
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
        Ok(())
    }
}

/// The contact force model the settings ask for: `Some` with that model.
pub(super) fn force_model_of(params: &CollisionParams) -> Option<ContactForceModel> {
    let mut model = match params.model {
        ContactModel::SpringDashpot { stiffness, damping } => ContactForceModel::new(stiffness, damping),
        ContactModel::Hertz { cohesion, .. } => {
            let e_star = params.model.effective_modulus()?;
            ContactForceModel::of(NormalLaw::hertz(e_star, cohesion), DampingLaw::CoeffRestitution)
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
        // (rolling friction asks for both rolling and twisting resistance)
        rolling: (params.rolling_friction > 0.0).then_some(RollingLaw::Sds {
            friction: params.rolling_friction,
            stiffness: t.rolling_stiffness,
            damping: t.rolling_damping,
        }),
        twisting: (params.rolling_friction > 0.0).then_some(TwistingLaw::Marshall),
    })
}
