//! The table of the force models' sub-models. LAMMPS GRANULAR's `pair granular` composes a
//! contact of five sub-models — normal, damping, tangential, rolling, twisting —, each a
//! class registered in its style table; kinema composes [`ContactForceModel`](super::ContactForceModel)
//! of the same five, each a closed choice in its own file:
//!
//! | kind | the law | its file |
//! |---|---|---|
//! | normal | [`NormalLaw`](super::NormalLaw) | `normal.rs` (with `cohesion.rs`: DMT, JKR) |
//! | damping | [`DampingLaw`](super::DampingLaw) | `damping.rs` |
//! | tangential | [`TangentialLaw`](super::TangentialLaw) | `tangent.rs` |
//! | rolling | [`RollingLaw`](super::RollingLaw) | `rolling.rs` |
//! | twisting | [`TwistingLaw`](super::TwistingLaw) | `twisting.rs` |
//!
//! [`SUB_MODELS`] is the register: one row per law, with LAMMPS's name and the setting that
//! chooses it, which the binding gives Python (`_core.CONTACT_SUB_MODELS`) and
//! docs/collisions.md's table is checked against. Each law's `NAMES` lists its variants in
//! the order of its `name` (whose every arm indexes `NAMES`, so a new variant grows it), and
//! the tests below hold the rows to those lists: a new law is its file's variant and arms,
//! and one row here (and its setting in `stage/settings.rs`).

use super::ContactForce;
#[cfg(test)]
use super::{DampingLaw, NormalLaw, RollingLaw, TangentialLaw, TwistingLaw};

/// Which part of a contact a sub-model is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SubModelKind {
    /// The elastic (and adhesive) force along the normal.
    Normal,
    /// The dashpot along the normal.
    Damping,
    /// The sliding friction's spring.
    Tangential,
    /// Rolling resistance.
    Rolling,
    /// Twisting resistance.
    Twisting,
}

impl SubModelKind {
    /// Its name, as LAMMPS's `pair granular` keyword.
    pub fn name(self) -> &'static str {
        match self {
            SubModelKind::Normal => "normal",
            SubModelKind::Damping => "damping",
            SubModelKind::Tangential => "tangential",
            SubModelKind::Rolling => "rolling",
            SubModelKind::Twisting => "twisting",
        }
    }
}

/// One sub-model of the table.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SubModel {
    /// The part of a contact it is.
    pub kind: SubModelKind,
    /// Its name, as its law's `name` gives it (LAMMPS's, but `hooke` for LAMMPS's `hooke`
    /// and `hertz` for its `hertz/material`).
    pub name: &'static str,
    /// LAMMPS GRANULAR's name for it.
    pub lammps: &'static str,
    /// The settings of `set_collisions` (and the scene's `[collisions]`) that choose it.
    pub chosen_by: &'static str,
}

/// The register of the sub-models (module doc).
pub const SUB_MODELS: [SubModel; 10] = [
    SubModel {
        kind: SubModelKind::Normal,
        name: "hooke",
        lammps: "hooke",
        chosen_by: "model=\"spring_dashpot\", stiffness",
    },
    SubModel {
        kind: SubModelKind::Normal,
        name: "hertz",
        lammps: "hertz/material",
        chosen_by: "model=\"hertz\", youngs_modulus, poisson_ratio",
    },
    SubModel {
        kind: SubModelKind::Normal,
        name: "dmt",
        lammps: "dmt",
        chosen_by: "model=\"hertz\", cohesion=\"dmt\", surface_energy",
    },
    SubModel {
        kind: SubModelKind::Normal,
        name: "jkr",
        lammps: "jkr",
        chosen_by: "model=\"hertz\", cohesion=\"jkr\", surface_energy",
    },
    SubModel {
        kind: SubModelKind::Damping,
        name: "coeff_restitution",
        lammps: "coeff_restitution",
        chosen_by: "restitution (the default)",
    },
    SubModel {
        kind: SubModelKind::Damping,
        name: "mass_velocity",
        lammps: "mass_velocity",
        chosen_by: "damping (model=\"spring_dashpot\")",
    },
    SubModel {
        kind: SubModelKind::Tangential,
        name: "linear_history",
        lammps: "linear_history",
        chosen_by: "friction > 0, tangential=\"linear_history\", tangential_stiffness, tangential_damping",
    },
    SubModel {
        kind: SubModelKind::Tangential,
        name: "mindlin",
        lammps: "mindlin",
        chosen_by: "friction > 0, tangential=\"mindlin\" (model=\"hertz\"), tangential_damping",
    },
    SubModel {
        kind: SubModelKind::Rolling,
        name: "sds",
        lammps: "sds",
        chosen_by: "rolling_friction > 0, rolling_stiffness, rolling_damping",
    },
    SubModel {
        kind: SubModelKind::Twisting,
        name: "marshall",
        lammps: "marshall",
        chosen_by: "rolling_friction > 0 (with rolling sds)",
    },
];

impl ContactForce<'_> {
    /// The sub-models its contacts are made of, by kind and name, in LAMMPS's order (the
    /// parts it has: a tangential part where some contact has friction, rolling and twisting
    /// with rolling friction): what `pair granular` would be given for the same contacts.
    pub fn sub_models(&self) -> Vec<(SubModelKind, &'static str)> {
        let mut out = vec![
            (SubModelKind::Normal, self.normal.name()),
            (SubModelKind::Damping, self.damping.name()),
        ];
        if let Some(t) = &self.tangential {
            out.push((SubModelKind::Tangential, t.law.name()));
            out.extend(t.rolling.map(|r| (SubModelKind::Rolling, r.name())));
            out.extend(t.twisting.map(|t| (SubModelKind::Twisting, t.name())));
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The names of the rows of `kind`, in the table's order.
    fn rows(kind: SubModelKind) -> Vec<&'static str> {
        SUB_MODELS.iter().filter(|m| m.kind == kind).map(|m| m.name).collect()
    }

    #[test]
    fn every_law_has_its_row_and_every_row_its_law() {
        assert_eq!(rows(SubModelKind::Normal), NormalLaw::NAMES);
        assert_eq!(rows(SubModelKind::Damping), DampingLaw::NAMES);
        assert_eq!(rows(SubModelKind::Tangential), TangentialLaw::NAMES);
        assert_eq!(rows(SubModelKind::Rolling), RollingLaw::NAMES);
        assert_eq!(rows(SubModelKind::Twisting), TwistingLaw::NAMES);
    }

    #[test]
    fn each_law_is_named_by_its_row() {
        use crate::collide::contact_force::Cohesion;
        let normal = [
            NormalLaw::Hooke { stiffness: 1.0 },
            NormalLaw::hertz(1.0, None),
            NormalLaw::hertz(1.0, Some(Cohesion::Dmt { surface_energy: 1.0 })),
            NormalLaw::hertz(1.0, Some(Cohesion::Jkr { surface_energy: 1.0 })),
        ];
        assert_eq!(normal.map(|l| l.name()), NormalLaw::NAMES);
        assert_eq!(
            [DampingLaw::of(None), DampingLaw::of(Some(1.0))].map(|l| l.name()),
            DampingLaw::NAMES
        );
        let tangential = [
            TangentialLaw::LinearHistory { stiffness: 1.0 },
            TangentialLaw::Mindlin { shear_modulus: 1.0 },
        ];
        assert_eq!(tangential.map(|l| l.name()), TangentialLaw::NAMES);
        let rolling = RollingLaw::Sds {
            friction: 0.1,
            stiffness: None,
            damping: None,
        };
        assert_eq!([rolling.name()], RollingLaw::NAMES);
        assert_eq!([TwistingLaw::Marshall.name()], TwistingLaw::NAMES);
    }
}
