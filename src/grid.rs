//! The discrete depth set I = {z_1, …, z_n} ⊂ [0,1] on which Algorithm 1 places Diracs
//! (Peters & Klein 2015, Section 3.1).

use anyhow::{bail, Result};

/// Number of uniform grid points where a command or candidate does not name its grid.
pub const DEFAULT_POINTS: usize = 1024;

/// Largest accepted grid (an LP's table holds n·m values per solver instance).
pub const MAX_POINTS: usize = 1 << 20;

/// A sorted set of at least two distinct, finite depths.
#[derive(Clone, Debug, PartialEq)]
pub struct Grid {
    points: Vec<f64>,
}

impl Grid {
    /// n uniform points z_i = i/(n−1), i = 0..n−1, including 0 and 1.
    pub fn uniform(n: usize) -> Result<Grid> {
        if n < 2 {
            bail!("grid: need at least 2 points, got {n}");
        }
        let d = (n - 1) as f64;
        Ok(Grid {
            points: (0..n).map(|i| i as f64 / d).collect(),
        })
    }

    /// n uniform points on [lo, hi] (used e.g. for the Hamburger problem on I = R,
    /// approximated by a wide interval such as [−1, 2]).
    pub fn uniform_on(n: usize, lo: f64, hi: f64) -> Result<Grid> {
        if !(lo.is_finite() && hi.is_finite() && lo < hi) {
            bail!("grid: invalid interval [{lo}, {hi}]");
        }
        let g = Grid::uniform(n)?;
        Ok(Grid {
            points: g.points.iter().map(|t| lo + (hi - lo) * t).collect(),
        })
    }

    /// An explicit list of points; sorted, duplicates removed.
    pub fn from_values(mut values: Vec<f64>) -> Result<Grid> {
        if let Some((i, v)) = values.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            bail!("grid: value {i} is not finite ({v})");
        }
        values.sort_by(|a, b| a.partial_cmp(b).unwrap());
        values.dedup();
        if values.len() < 2 {
            bail!(
                "grid: need at least 2 distinct points, got {}",
                values.len()
            );
        }
        Ok(Grid { points: values })
    }

    /// z_1 < … < z_n.
    pub fn points(&self) -> &[f64] {
        &self.points
    }

    /// n, the number of points.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// Index of the grid point nearest to z (ties to the lower point; outside the grid: an
    /// end).
    pub fn nearest(&self, z: f64) -> usize {
        let p = &self.points;
        let i = p.partition_point(|&g| g < z);
        if i == 0 {
            0
        } else if i == p.len() || z - p[i - 1] <= p[i] - z {
            i - 1
        } else {
            i
        }
    }

    /// The grid point nearest to z ([`Grid::nearest`]; monotone in z): a depth snapped to I.
    pub fn snap(&self, z: f64) -> f64 {
        self.points[self.nearest(z)]
    }

    /// True when n = 0 (never, once built).
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uniform_has_endpoints_and_spacing() {
        let g = Grid::uniform(5).unwrap();
        assert_eq!(g.points(), &[0.0, 0.25, 0.5, 0.75, 1.0]);
        assert!(Grid::uniform(1).is_err());
    }

    #[test]
    fn from_values_sorts_and_rejects_bad() {
        let g = Grid::from_values(vec![0.5, 0.1, 0.5, 0.9]).unwrap();
        assert_eq!(g.points(), &[0.1, 0.5, 0.9]);
        assert!(Grid::from_values(vec![0.1, f64::NAN]).is_err());
        assert!(Grid::from_values(vec![0.3, 0.3]).is_err());
    }
}
