//! Shadow techniques: everything that turns filtered moments b and a fragment depth z_f into a
//! shadow intensity G ∈ [0,1] (0 = lit, 1 = fully shadowed). LP candidates (Algorithm 1 with any
//! basis) and closed-form solvers (Hamburger/Hausdorff MSM, TMSM, VSM, ESM, EVSM, CSM) implement
//! the same [`Technique`] trait, so evaluation, benchmarks and stability code are written once.
//! One file per technique.

/// A filterable shadow-map technique.
///
/// The shadow map stores b(z) per texel; filtering gives the moments b = Σ w_l b(z_l) of the
/// depth distribution; [`Evaluator::shadow`] turns (b, z_f) into a shadow intensity.
pub trait Technique: Send + Sync {
    /// Short name used on the CLI and in reports (e.g. "hamburger4", "lp[z,z^2]").
    fn name(&self) -> String;
    /// Number m of stored values per texel.
    fn moment_count(&self) -> usize;
    /// The basis: `out[j] = b_j(z)` for one depth z (`out.len() == moment_count()`).
    fn basis(&self, z: f64, out: &mut [f64]);
    /// Bits stored per shadow-map texel (for the speed/accuracy chart).
    fn bits_per_texel(&self) -> u32 {
        32 * self.moment_count() as u32
    }
    /// The discrete depth set I when the technique is Algorithm 1 on a grid (LP candidates):
    /// evaluation snaps kernel depths and z_f to the nearest grid point so the moments are
    /// always those of a distribution on I. `None` for closed-form techniques (exact depths).
    fn depth_grid(&self) -> Option<&crate::Grid> {
        None
    }
    /// A per-thread evaluator. Closed-form techniques return a stateless wrapper
    /// ([`Stateless`]); LP candidates keep warm-start state in theirs.
    fn evaluator(&self) -> Box<dyn Evaluator + '_>;
    /// The receiver depths z_f on which the technique's formula is defined (see
    /// [`DepthDomain`]). Default: [0,1].
    fn depth_domain(&self) -> DepthDomain {
        DepthDomain::UnitInterval
    }
}

/// The receiver depths z_f a technique's formula is defined on. Engines pass biased depths
/// z − ε that can leave [0,1] near the light or the far plane; [`DepthDomain::shadow`] answers
/// every finite z_f.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DepthDomain {
    /// Every real z_f: Hamburger MSM (sharp bound over distributions on ℝ, Peters & Klein 2015,
    /// Section 3), VSM (Chebyshev–Cantelli), ESM and EVSM (exponential warps of any depth).
    Real,
    /// z_f in [0,1]: Hausdorff MSM, TMSM, CSM and LP candidates bound P(Z < z_f) over depth
    /// distributions on [0,1]. Outside, the sharp bound extends exactly: G = 0 for z_f < 0
    /// (no mass below 0) and G = F_Z(1) = 1 for z_f > 1 (all mass below z_f).
    UnitInterval,
}

impl DepthDomain {
    /// G(b, z_f) for any finite z_f: the evaluator's answer inside the domain; for
    /// [`DepthDomain::UnitInterval`] 0 below 0 and 1 above 1 without calling it.
    pub fn shadow(self, ev: &mut (impl Evaluator + ?Sized), moments: &[f64], zf: f64) -> f64 {
        match self {
            DepthDomain::UnitInterval if zf < 0.0 => 0.0,
            DepthDomain::UnitInterval if zf > 1.0 => 1.0,
            _ => ev.shadow(moments, zf),
        }
    }
}

/// Evaluates shadow intensities; may keep state between calls (LP warm start).
pub trait Evaluator {
    /// Shadow intensity G(b, z_f) ∈ [0,1] from filtered moments `moments` at depth `zf`.
    fn shadow(&mut self, moments: &[f64], zf: f64) -> f64;
    /// Calls so far whose answer was unsettled (an LP the solver could not certify either way,
    /// scored as the trivial bound G = 0: see [`crate::lp::UNSETTLED_G`]). Closed forms: 0.
    fn unsettled(&self) -> usize {
        0
    }
    /// Forget warm-start state (the next answers are those of a new evaluator, the counters
    /// stay). Closed forms: nothing to do.
    fn reset(&mut self) {}
}

/// Closed-form techniques: a pure function of (b, z_f).
pub trait ClosedForm: Send + Sync {
    /// The shadow intensity G(b, z_f) for the stored moments b (the technique applies its bias) at fragment depth z_f.
    fn shadow(&self, moments: &[f64], zf: f64) -> f64;
}

/// Wraps a [`ClosedForm`] as an [`Evaluator`].
pub struct Stateless<'a, T: ?Sized>(pub &'a T);

impl<T: ClosedForm + ?Sized> Evaluator for Stateless<'_, T> {
    fn shadow(&mut self, moments: &[f64], zf: f64) -> f64 {
        self.0.shadow(moments, zf)
    }
}

/// The [`Technique::evaluator`] of a [`ClosedForm`] technique, written inside its
/// `impl Technique`: a [`Stateless`] wrapper around `self`.
macro_rules! stateless_evaluator {
    () => {
        fn evaluator(&self) -> Box<dyn $crate::technique::Evaluator + '_> {
            Box::new($crate::technique::Stateless(self))
        }
    };
}

pub mod csm;
pub mod esm;
pub mod evsm;
pub mod hamburger;
pub mod hamburger4;
pub mod hamburger6;
pub mod hausdorff4;
pub mod linalg;
pub mod lp_candidate;
pub mod registry;
pub mod roots;
pub mod vsm;
pub use registry::by_name;
pub mod sparse;
pub mod timing;
pub mod tmsm;
