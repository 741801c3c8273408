//! The registry of method names, shared by Rust, Python, scenes and the command line.

use std::fmt;
use std::str::FromStr;

use super::tableau::{catalogue, ButcherTableau};
use crate::error::Error;

/// How a method advances a step.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MethodKind {
    /// Explicit Runge–Kutta with a fixed step, run from its Butcher tableau.
    ExplicitRk,
    /// Implicit: solves a nonlinear equation per step (Newton iterations).
    Implicit,
    /// Explicit Runge–Kutta with an embedded error estimate and step-size control.
    Adaptive,
    /// Only for second-order systems x'' = a(t, x, v) (symplectic, splitting x and v).
    SecondOrder,
}

/// A named integration method.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Method {
    /// Forward (explicit) Euler, order 1.
    Euler,
    /// Explicit midpoint, order 2.
    Midpoint,
    /// Heun's method (explicit trapezoid), order 2.
    Heun,
    /// Classical Runge–Kutta, order 4.
    Rk4,
    /// Backward (implicit) Euler, order 1, A-stable (L-stable).
    ImplicitEuler,
    /// Dormand–Prince 5(4), adaptive.
    Rk45,
    /// Symplectic (semi-implicit) Euler: kick, then drift. Order 1. Second-order systems.
    SymplecticEuler,
    /// Velocity Verlet, order 2, symplectic. Second-order systems.
    Verlet,
}

/// Other names of the registered methods, in textbooks, the lecture notes (`../seed`) and
/// other libraries (SciPy's `RK45`, MATLAB's `ode45`), for [`Method::suggestion`]; lower
/// case, words joined by `_`.
pub const OTHER_NAMES: [(&str, Method); 22] = [
    ("explicit_euler", Method::Euler),
    ("forward_euler", Method::Euler),
    ("euler_forward", Method::Euler),
    ("explicit_midpoint", Method::Midpoint),
    ("modified_euler", Method::Heun),
    ("improved_euler", Method::Heun),
    ("explicit_trapezoid", Method::Heun),
    ("runge_kutta", Method::Rk4),
    ("classical_rk4", Method::Rk4),
    ("runge_kutta_4", Method::Rk4),
    ("backward_euler", Method::ImplicitEuler),
    ("euler_backward", Method::ImplicitEuler),
    ("implicit", Method::ImplicitEuler),
    ("dopri5", Method::Rk45),
    ("dormand_prince", Method::Rk45),
    ("ode45", Method::Rk45),
    ("semi_implicit_euler", Method::SymplecticEuler),
    ("euler_cromer", Method::SymplecticEuler),
    ("velocity_verlet", Method::Verlet),
    ("leapfrog", Method::Verlet),
    ("stormer_verlet", Method::Verlet),
    ("störmer_verlet", Method::Verlet),
];

impl Method {
    /// Every registered method, in the order they are documented.
    pub const ALL: [Method; 8] = [
        Method::Euler,
        Method::Midpoint,
        Method::Heun,
        Method::Rk4,
        Method::ImplicitEuler,
        Method::Rk45,
        Method::SymplecticEuler,
        Method::Verlet,
    ];

    /// The registered name (`"rk4"`).
    pub fn name(self) -> &'static str {
        match self {
            Method::Euler => "euler",
            Method::Midpoint => "midpoint",
            Method::Heun => "heun",
            Method::Rk4 => "rk4",
            Method::ImplicitEuler => "implicit_euler",
            Method::Rk45 => "rk45",
            Method::SymplecticEuler => "symplectic_euler",
            Method::Verlet => "verlet",
        }
    }

    /// Looks a name up; the error lists every valid name, and the one meant where
    /// [`Method::suggestion`] finds it ("did you mean 'rk4'?").
    pub fn from_name(name: &str) -> Result<Self, Error> {
        Method::ALL
            .iter()
            .copied()
            .find(|m| m.name() == name)
            .ok_or_else(|| Error::UnknownMethod {
                name: name.to_string(),
                hint: Method::suggestion(name)
                    .map(|m| format!(" did you mean '{}'?", m.name()))
                    .unwrap_or_default(),
                valid: Method::ALL.iter().map(|m| m.name()).collect::<Vec<_>>().join(", "),
            })
    }

    /// The registered method an unknown name probably means: the same name in other capitals
    /// or separators (`RK4`, `Implicit-Euler`), a name the literature and the lecture notes give
    /// it ([`OTHER_NAMES`]: `forward_euler`, `backward_euler`, `leapfrog`), or else a
    /// registered or other name within two edits of it (a typo: `verlett`, `rk54`); `None`
    /// when nothing is that close. Only for messages: a name is never taken for another.
    pub fn suggestion(name: &str) -> Option<Method> {
        let plain: String = name
            .trim()
            .chars()
            .map(|c| if c == '-' || c == ' ' { '_' } else { c.to_ascii_lowercase() })
            .collect();
        let names = Method::ALL.iter().map(|&m| (m.name(), m)).chain(OTHER_NAMES.iter().copied());
        if let Some((_, m)) = names.clone().find(|(n, _)| *n == plain) {
            return Some(m);
        }
        names
            .map(|(n, m)| (strsim::levenshtein(n, &plain), m))
            .filter(|&(d, _)| d <= 2)
            .min_by_key(|&(d, _)| d)
            .map(|(_, m)| m)
    }

    /// How it steps.
    pub fn kind(self) -> MethodKind {
        match self {
            Method::Euler | Method::Midpoint | Method::Heun | Method::Rk4 => MethodKind::ExplicitRk,
            Method::ImplicitEuler => MethodKind::Implicit,
            Method::Rk45 => MethodKind::Adaptive,
            Method::SymplecticEuler | Method::Verlet => MethodKind::SecondOrder,
        }
    }

    /// Order of accuracy p (global error O(hᵖ)).
    pub fn order(self) -> u32 {
        match self {
            Method::Euler | Method::ImplicitEuler | Method::SymplecticEuler => 1,
            Method::Midpoint | Method::Heun | Method::Verlet => 2,
            Method::Rk4 => 4,
            Method::Rk45 => 5,
        }
    }

    /// Right-hand-side evaluations per step (FSAL reuse counted; rk45 per accepted step
    /// without rejections; implicit Euler: per Newton iteration, plus one per unknown of a
    /// system (of a batch member, in a batch) for each finite-difference Jacobian).
    pub fn evals_per_step(self) -> u32 {
        match self {
            Method::Euler | Method::ImplicitEuler | Method::SymplecticEuler | Method::Verlet => 1,
            Method::Midpoint | Method::Heun => 2,
            Method::Rk4 => 4,
            Method::Rk45 => 6,
        }
    }

    /// One line for listings and help texts.
    pub fn summary(self) -> &'static str {
        match self {
            Method::Euler => "forward Euler: y += h f(t, y)",
            Method::Midpoint => "explicit midpoint: slope taken at the half step",
            Method::Heun => "Heun: Euler predictor, trapezoidal corrector",
            Method::Rk4 => "classical Runge-Kutta, weights 1/6 1/3 1/3 1/6",
            Method::ImplicitEuler => "backward Euler: y_{n+1} = y_n + h f(t_{n+1}, y_{n+1}), Newton iterations",
            Method::Rk45 => "Dormand-Prince 5(4), adaptive step with a PI controller",
            Method::SymplecticEuler => "symplectic Euler: v += h a(x, v); x += h v (second-order systems)",
            Method::Verlet => "velocity Verlet: half kick, drift, half kick (second-order systems)",
        }
    }

    /// The Butcher tableau of the explicit Runge–Kutta methods (rk45: Dormand–Prince).
    pub fn tableau(self) -> Option<ButcherTableau> {
        match self {
            Method::Euler => Some(catalogue::euler()),
            Method::Midpoint => Some(catalogue::midpoint()),
            Method::Heun => Some(catalogue::heun()),
            Method::Rk4 => Some(catalogue::rk4()),
            Method::Rk45 => Some(catalogue::dopri5()),
            _ => None,
        }
    }
}

impl fmt::Display for Method {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Method {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self, Error> {
        Method::from_name(s)
    }
}

/// What a solver is asked to use: a registered method or a user's explicit tableau.
#[derive(Debug, Clone, PartialEq)]
pub enum Integrator {
    /// A method from the registry.
    Named(Method),
    /// A user-supplied explicit Runge–Kutta method, run with a fixed step.
    Tableau(ButcherTableau),
}

impl Integrator {
    /// Name for messages: the registered name or the tableau's own.
    pub fn name(&self) -> &str {
        match self {
            Integrator::Named(m) => m.name(),
            Integrator::Tableau(t) => t.name(),
        }
    }
    /// Order of accuracy.
    pub fn order(&self) -> u32 {
        match self {
            Integrator::Named(m) => m.order(),
            Integrator::Tableau(t) => t.order(),
        }
    }
}

impl From<Method> for Integrator {
    fn from(m: Method) -> Self {
        Integrator::Named(m)
    }
}

impl From<ButcherTableau> for Integrator {
    fn from(t: ButcherTableau) -> Self {
        Integrator::Tableau(t)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip() {
        for m in Method::ALL {
            assert_eq!(Method::from_name(m.name()).unwrap(), m);
        }
    }

    #[test]
    fn an_unknown_name_is_told_the_method_it_probably_means() {
        // The lecture's and the textbooks' names, other capitals and separators, typos;
        // nothing for a name far from all of them. A suggestion is never taken for the name.
        for (asked, meant) in [
            ("RK4", "rk4"),
            ("explicit_euler", "euler"),
            ("forward_euler", "euler"),
            ("Forward Euler", "euler"),
            ("backward_euler", "implicit_euler"),
            ("Implicit-Euler", "implicit_euler"),
            ("leapfrog", "verlet"),
            ("velocity_verlet", "verlet"),
            ("verlett", "verlet"),
            ("euler_cromer", "symplectic_euler"),
            ("RK45", "rk45"),
            ("ode45", "rk45"),
        ] {
            assert_eq!(Method::suggestion(asked).map(Method::name), Some(meant), "{asked}");
            let e = Method::from_name(asked).unwrap_err().to_string();
            assert!(
                e.contains(&format!("'{asked}'; did you mean '{meant}'? valid methods are: euler")),
                "{e}"
            );
        }
        for far in ["", "gear", "adams_bashforth", "bdf2"] {
            assert_eq!(Method::suggestion(far), None, "{far}");
            let e = Method::from_name(far).unwrap_err().to_string();
            assert!(!e.contains("did you mean") && e.contains("; valid methods are: euler"), "{e}");
        }
    }

    #[test]
    fn unknown_names_list_the_valid_ones() {
        let e = Method::from_name("rk5").unwrap_err().to_string();
        assert!(
            e.contains("'rk5'") && e.contains("euler, midpoint, heun, rk4, implicit_euler, rk45, symplectic_euler, verlet"),
            "{e}"
        );
    }

    #[test]
    fn tableau_orders_agree_with_the_registry() {
        for m in Method::ALL {
            if let Some(t) = m.tableau() {
                assert_eq!(t.order(), m.order(), "{m}");
            }
        }
    }
}
