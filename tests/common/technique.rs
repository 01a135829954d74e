//! A configurable test technique, and TMSM moments of Dirac mixtures.

use momentlab::technique::{tmsm, Evaluator, Technique};
use momentlab::Grid;

/// The shadow a [`Mock`] answers for (moments, z_f).
pub type Shadow = Box<dyn Fn(&[f64], f64) -> f64 + Send + Sync>;

/// A technique with a given name, basis, optional depth grid and shadow function.
pub struct Mock {
    pub name: &'static str,
    pub m: usize,
    pub basis: fn(f64, &mut [f64]),
    pub grid: Option<Grid>,
    pub shadow: Shadow,
}

impl Mock {
    /// Without a depth grid.
    pub fn new(
        name: &'static str,
        m: usize,
        basis: fn(f64, &mut [f64]),
        shadow: impl Fn(&[f64], f64) -> f64 + Send + Sync + 'static,
    ) -> Mock {
        Mock {
            name,
            m,
            basis,
            grid: None,
            shadow: Box::new(shadow),
        }
    }
}

struct MockEval<'a>(&'a Mock);

impl Evaluator for MockEval<'_> {
    fn shadow(&mut self, b: &[f64], zf: f64) -> f64 {
        (self.0.shadow)(b, zf)
    }
}

impl Technique for Mock {
    fn name(&self) -> String {
        self.name.into()
    }
    fn moment_count(&self) -> usize {
        self.m
    }
    fn basis(&self, z: f64, out: &mut [f64]) {
        (self.basis)(z, out)
    }
    fn depth_grid(&self) -> Option<&Grid> {
        self.grid.as_ref()
    }
    fn evaluator(&self) -> Box<dyn Evaluator + '_> {
        Box::new(MockEval(self))
    }
}

/// The TMSM moments of the Dirac mixture `atoms` (z, w).
pub fn tmsm_moments(atoms: &[(f64, f64)]) -> [f64; 4] {
    let mut b = [0.0; 4];
    let mut row = [0.0; 4];
    for &(z, w) in atoms {
        tmsm::basis(z, &mut row);
        for j in 0..4 {
            b[j] += w * row[j];
        }
    }
    b
}
