//! What is integrated: first-order systems y' = f(t, y) and second-order systems
//! x'' = a(t, x, v), kept apart from how a step advances (the integrators) and when to step
//! (the drivers in `solve`).

use crate::error::CallbackError;

/// A first-order system of ODEs y'(t) = f(t, y), y ∈ ℝⁿ.
///
/// A system may consist of `dim() / block_len()` independent copies of one smaller system
/// (the batch mode: many initial conditions solved together). Blocks never couple, which lets
/// implicit methods treat the Jacobian as block diagonal and lets error control weigh each
/// block on its own.
pub trait OdeSystem {
    /// Number of unknowns n.
    fn dim(&self) -> usize;

    /// Writes f(t, y) into `dydt` (length n). `t` in the problem's time unit (s by default).
    fn rhs(&mut self, t: f64, y: &[f64], dydt: &mut [f64]) -> Result<(), CallbackError>;

    /// Length of one independent block; `dim()` (one block) unless batched.
    fn block_len(&self) -> usize {
        self.dim()
    }

    /// Whether [`OdeSystem::jacobian`] is available; otherwise implicit methods use finite
    /// differences of `rhs`.
    fn has_jacobian(&self) -> bool {
        false
    }

    /// Writes the Jacobian ∂f/∂y at (t, y) as the diagonal blocks, each `block_len × block_len`
    /// row-major, one after the other (`dim() * block_len()` values in all). Only called when
    /// [`OdeSystem::has_jacobian`] is true.
    fn jacobian(&mut self, _t: f64, _y: &[f64], _jac: &mut [f64]) -> Result<(), CallbackError> {
        Err("this system provides no Jacobian".into())
    }
}

/// A second-order system x''(t) = a(t, x, v) with v = x', x ∈ ℝⁿ: Newton's law for particles,
/// a = F/m.
pub trait SecondOrderSystem {
    /// Number of coordinates n (the first-order form has 2n unknowns).
    fn dim(&self) -> usize;

    /// Writes the acceleration a(t, x, v) into `acc` (length n).
    fn accel(&mut self, t: f64, x: &[f64], v: &[f64], acc: &mut [f64]) -> Result<(), CallbackError>;

    /// Length of one independent block of coordinates; `dim()` unless batched.
    fn block_len(&self) -> usize {
        self.dim()
    }
}

/// A closure as a first-order system: `FnSystem::new(n, |t, y, dydt| { ...; Ok(()) })`.
pub struct FnSystem<F> {
    dim: usize,
    f: F,
}

impl<F> FnSystem<F>
where
    F: FnMut(f64, &[f64], &mut [f64]) -> Result<(), CallbackError>,
{
    /// Wraps `f` as a system of `dim` unknowns.
    pub fn new(dim: usize, f: F) -> Self {
        Self { dim, f }
    }
}

impl<F> OdeSystem for FnSystem<F>
where
    F: FnMut(f64, &[f64], &mut [f64]) -> Result<(), CallbackError>,
{
    fn dim(&self) -> usize {
        self.dim
    }
    fn rhs(&mut self, t: f64, y: &[f64], dydt: &mut [f64]) -> Result<(), CallbackError> {
        (self.f)(t, y, dydt)
    }
}

/// A closure as a second-order system: `FnSecondOrder::new(n, |t, x, v, a| { ...; Ok(()) })`.
pub struct FnSecondOrder<F> {
    dim: usize,
    a: F,
}

impl<F> FnSecondOrder<F>
where
    F: FnMut(f64, &[f64], &[f64], &mut [f64]) -> Result<(), CallbackError>,
{
    /// Wraps `a` as a system of `dim` coordinates.
    pub fn new(dim: usize, a: F) -> Self {
        Self { dim, a }
    }
}

impl<F> SecondOrderSystem for FnSecondOrder<F>
where
    F: FnMut(f64, &[f64], &[f64], &mut [f64]) -> Result<(), CallbackError>,
{
    fn dim(&self) -> usize {
        self.dim
    }
    fn accel(&mut self, t: f64, x: &[f64], v: &[f64], acc: &mut [f64]) -> Result<(), CallbackError> {
        (self.a)(t, x, v, acc)
    }
}

/// The first-order form of a second-order system: y = [x₁..xₙ, v₁..vₙ], y' = [v, a(t, x, v)].
///
/// With batching, each block of the first-order form is [x_block, v_block] so that blocks stay
/// contiguous: y = [x⁽¹⁾, v⁽¹⁾, x⁽²⁾, v⁽²⁾, ...].
pub struct FirstOrderForm<'a> {
    inner: &'a mut dyn SecondOrderSystem,
    x: Vec<f64>,
    v: Vec<f64>,
    a: Vec<f64>,
}

impl<'a> FirstOrderForm<'a> {
    /// Wraps a second-order system.
    pub fn new(inner: &'a mut dyn SecondOrderSystem) -> Self {
        let n = inner.dim();
        Self {
            inner,
            x: vec![0.0; n],
            v: vec![0.0; n],
            a: vec![0.0; n],
        }
    }

    /// Splits a first-order state into x and v (each of length n), block by block.
    pub fn split(y: &[f64], block: usize, x: &mut [f64], v: &mut [f64]) {
        for (k, yb) in y.chunks_exact(2 * block).enumerate() {
            x[k * block..(k + 1) * block].copy_from_slice(&yb[..block]);
            v[k * block..(k + 1) * block].copy_from_slice(&yb[block..]);
        }
    }

    /// Joins x and v into a first-order state, block by block (inverse of [`Self::split`]).
    pub fn join(x: &[f64], v: &[f64], block: usize, y: &mut [f64]) {
        for (k, yb) in y.chunks_exact_mut(2 * block).enumerate() {
            yb[..block].copy_from_slice(&x[k * block..(k + 1) * block]);
            yb[block..].copy_from_slice(&v[k * block..(k + 1) * block]);
        }
    }
}

impl OdeSystem for FirstOrderForm<'_> {
    fn dim(&self) -> usize {
        2 * self.inner.dim()
    }
    fn block_len(&self) -> usize {
        2 * self.inner.block_len()
    }
    fn rhs(&mut self, t: f64, y: &[f64], dydt: &mut [f64]) -> Result<(), CallbackError> {
        let b = self.inner.block_len();
        Self::split(y, b, &mut self.x, &mut self.v);
        self.inner.accel(t, &self.x, &self.v, &mut self.a)?;
        // dx/dt = v, dv/dt = a
        Self::join(&self.v, &self.a, b, dydt);
        Ok(())
    }
}
