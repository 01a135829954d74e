//! The answer of a race as sets: the winner, the candidates statistically tied for first (or
//! unresolved, when an LP budget ended the race), the candidates eliminated by confidence;
//! and the check of a race against
//! an exhaustive run of the same data (docs/search.md, "Validation").

use super::race::Elimination;
use super::results::Row;
use anyhow::{bail, Result};
use std::collections::{HashMap, HashSet};

/// The race outcome read from result rows.
#[derive(Clone, Debug, PartialEq)]
pub struct TieSet {
    /// The winner: the best survivor (racing) or the best candidate scored on every fragment.
    pub winner: Option<Row>,
    /// Survivors, statistically tied for first, by error (the winner first).
    pub tied: Vec<Row>,
    /// Duplicate-span candidates of tied ones (same G, hence tied too).
    pub tied_duplicates: usize,
    /// Survivors of a race the LP budget ended (not completed), by their estimate.
    pub unresolved: Vec<Row>,
    /// Eliminated by confidence.
    pub confidence: usize,
    /// Rows carry racing decisions (false: exhaustive or older results).
    pub raced: bool,
}

impl TieSet {
    /// The certified set: tied ∪ unresolved (contains the best at the stated confidence).
    pub fn certified(&self) -> HashSet<u64> {
        self.tied
            .iter()
            .chain(&self.unresolved)
            .map(|r| r.index)
            .collect()
    }
}

fn by_error(v: &mut [Row]) {
    v.sort_by(|a, b| {
        a.error
            .unwrap_or(f64::INFINITY)
            .total_cmp(&b.error.unwrap_or(f64::INFINITY))
            .then(a.index.cmp(&b.index))
    });
}

/// The winner of `rows`: the best tied row, else the best unresolved row (by its estimate),
/// else the best row scored on every fragment, else the best row.
pub fn winner_of(rows: &[Row]) -> Option<Row> {
    let best = |f: &dyn Fn(&Row) -> bool| {
        let mut v: Vec<Row> = rows
            .iter()
            .filter(|r| r.error.is_some() && f(r))
            .cloned()
            .collect();
        by_error(&mut v);
        v.into_iter().next()
    };
    best(&|r| r.tied)
        .or_else(|| best(&|r| r.unresolved))
        .or_else(|| best(&|r| r.full))
        .or_else(|| best(&|_| true))
}

/// The sets of a results file.
pub fn tie_set(rows: &[Row]) -> TieSet {
    let mut tied: Vec<Row> = rows.iter().filter(|r| r.tied).cloned().collect();
    let mut unresolved: Vec<Row> = rows.iter().filter(|r| r.unresolved).cloned().collect();
    by_error(&mut tied);
    by_error(&mut unresolved);
    let tied_ids: HashSet<u64> = tied.iter().map(|r| r.index).collect();
    TieSet {
        winner: winner_of(rows),
        tied_duplicates: rows
            .iter()
            .filter(|r| r.duplicate_of.is_some_and(|d| tied_ids.contains(&d)))
            .count(),
        confidence: rows
            .iter()
            .filter(|r| r.eliminated == Some(Elimination::Confidence))
            .count(),
        raced: !tied.is_empty()
            || !unresolved.is_empty()
            || rows.iter().any(|r| r.eliminated.is_some()),
        tied,
        unresolved,
    }
}

/// What happened to a candidate in the race, in words ("tied for first", "eliminated by
/// confidence in stage 2", …).
pub fn status(r: &Row) -> String {
    match (r.tied, r.eliminated) {
        (true, _) => "tied for first".into(),
        (_, Some(Elimination::Confidence)) => format!(
            "worse (stage {}, look {}: Δ ≥ {:+.4} pp vs {})",
            r.stage,
            r.look.unwrap_or(0) + 1,
            r.diff_lower.unwrap_or(f64::NAN) * 100.0,
            r.versus.map_or("?".into(), |v| v.to_string())
        ),
        _ if r.unresolved => format!("unresolved (LP budget, after stage {})", r.stage),
        _ if r.degenerate => "degenerate".into(),
        _ if r.duplicate_of.is_some() => "duplicate".into(),
        _ if r.full => "all fragments".into(),
        _ => "sample".into(),
    }
}

/// A race checked against an exhaustive run of the same candidates and fragments.
#[derive(Clone, Debug, PartialEq)]
pub struct Validation {
    /// The exhaustive winner and its error.
    pub exhaustive_winner: u64,
    /// The exhaustive winner's error.
    pub exhaustive_error: f64,
    /// The race winner and its exhaustive error.
    pub race_winner: u64,
    /// The race winner's exhaustive error.
    pub race_winner_error: f64,
    /// Status of the exhaustive winner in the race.
    pub exhaustive_winner_status: String,
    /// The exhaustive winner is tied / in the certified set (tied ∪ unresolved).
    pub winner_tied: bool,
    /// The exhaustive winner is in the certified set (tied ∪ unresolved).
    pub winner_certified: bool,
    /// Confidence-eliminated candidates with an exhaustive error ≤ the race winner's.
    pub eliminated_better_than_winner: Vec<u64>,
    /// Confidence-eliminated candidates with an exhaustive error ≤ that of their stage
    /// reference: the false eliminations (`--correction all` bounds them all together).
    pub false_eliminations: Vec<u64>,
    /// Candidates tied for first in the race.
    pub tied: usize,
    /// Candidates the LP budget left unresolved.
    pub unresolved: usize,
    /// Candidates eliminated by confidence.
    pub confidence: usize,
    /// Rank (exhaustive) of the worst tied candidate.
    pub worst_tied_rank: usize,
}

/// Check the race `race` against `exhaustive` (every candidate on every fragment of the same
/// dataset): both must hold the same candidates.
pub fn validate(race: &[Row], exhaustive: &[Row]) -> Result<Validation> {
    let ex: HashMap<u64, f64> = exhaustive
        .iter()
        .filter_map(|r| r.error.map(|e| (r.index, e)))
        .collect();
    if exhaustive.iter().any(|r| r.error.is_some() && !r.full) {
        bail!("validate: the exhaustive results hold rows not scored on every fragment");
    }
    let scored: Vec<u64> = race
        .iter()
        .filter(|r| r.error.is_some())
        .map(|r| r.index)
        .collect();
    if let Some(i) = scored.iter().find(|i| !ex.contains_key(i)) {
        bail!("validate: candidate {i} of the race is not in the exhaustive results");
    }
    let t = tie_set(race);
    let Some(rw) = &t.winner else {
        bail!("validate: the race has no winner");
    };
    let mut order: Vec<(f64, u64)> = scored.iter().map(|&i| (ex[&i], i)).collect();
    order.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    let (ew_err, ew) = order[0];
    let rank: HashMap<u64, usize> = order
        .iter()
        .enumerate()
        .map(|(k, x)| (x.1, k + 1))
        .collect();
    let rw_err = ex[&rw.index];
    let conf: Vec<&Row> = race
        .iter()
        .filter(|r| r.eliminated == Some(Elimination::Confidence))
        .collect();
    let ew_row = race.iter().find(|r| r.index == ew);
    Ok(Validation {
        exhaustive_winner: ew,
        exhaustive_error: ew_err,
        race_winner: rw.index,
        race_winner_error: rw_err,
        exhaustive_winner_status: ew_row.map_or("not in the race".into(), status),
        winner_tied: ew_row.is_some_and(|r| r.tied),
        winner_certified: t.certified().contains(&ew),
        eliminated_better_than_winner: conf
            .iter()
            .filter(|r| ex[&r.index] <= rw_err)
            .map(|r| r.index)
            .collect(),
        false_eliminations: conf
            .iter()
            .filter(|r| {
                r.versus
                    .and_then(|v| ex.get(&v))
                    .is_some_and(|&v| ex[&r.index] <= v)
            })
            .map(|r| r.index)
            .collect(),
        tied: t.tied.len(),
        unresolved: t.unresolved.len(),
        confidence: t.confidence,
        worst_tied_rank: t.tied.iter().map(|r| rank[&r.index]).max().unwrap_or(0),
    })
}

impl Validation {
    /// The check in words, one line per statement.
    pub fn lines(&self) -> Vec<String> {
        vec![
            format!(
                "exhaustive winner {} ({:.4} %): {} in the race; in the tied set: {}; in the certified set (tied ∪ unresolved): {}",
                self.exhaustive_winner,
                self.exhaustive_error * 100.0,
                self.exhaustive_winner_status,
                self.winner_tied,
                self.winner_certified
            ),
            format!(
                "race winner {} has exhaustive error {:.4} % (+{:.4} pp over the exhaustive winner)",
                self.race_winner,
                self.race_winner_error * 100.0,
                (self.race_winner_error - self.exhaustive_error) * 100.0
            ),
            format!(
                "{} tied (worst exhaustive rank {}), {} unresolved, {} eliminated by confidence",
                self.tied, self.worst_tied_rank, self.unresolved, self.confidence
            ),
            format!(
                "confidence-eliminated candidates better than the race winner on the full sample: {} {:?}",
                self.eliminated_better_than_winner.len(),
                self.eliminated_better_than_winner
            ),
            format!(
                "false eliminations (exhaustive error ≤ that of the stage reference): {} {:?}",
                self.false_eliminations.len(),
                self.false_eliminations
            ),
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(index: u64, e: f64, tied: bool, el: Option<Elimination>, versus: Option<u64>) -> Row {
        Row {
            error: Some(e),
            full: tied,
            tied,
            eliminated: el,
            versus,
            ..Row::plain(index, vec![format!("f{index}")])
        }
    }

    #[test]
    fn sets_and_validation() {
        let race = vec![
            row(0, 0.10, true, None, Some(0)),
            row(1, 0.11, true, None, Some(0)),
            Row {
                unresolved: true,
                ..row(2, 0.09, false, None, Some(0)) // sampled estimate
            },
            row(3, 0.30, false, Some(Elimination::Confidence), Some(0)),
            row(4, 0.20, false, Some(Elimination::Confidence), Some(1)),
        ];
        let t = tie_set(&race);
        assert_eq!(
            t.winner.as_ref().unwrap().index,
            0,
            "the best tied row, not a sample"
        );
        assert_eq!(t.tied.len(), 2);
        assert_eq!(t.unresolved.len(), 1);
        assert_eq!(t.confidence, 2);
        assert!(t.raced);
        // Exhaustive: candidate 1 is the best; 4 is better than its reference 1 (a false
        // elimination) and better than the race winner.
        let ex: Vec<Row> = [(0, 0.101), (1, 0.100), (2, 0.12), (3, 0.3), (4, 0.0995)]
            .iter()
            .map(|&(i, e)| Row {
                error: Some(e),
                full: true,
                ..Row::plain(i, vec![])
            })
            .collect();
        let v = validate(&race, &ex).unwrap();
        assert_eq!(v.exhaustive_winner, 4);
        assert!(!v.winner_tied && !v.winner_certified);
        assert_eq!(v.eliminated_better_than_winner, vec![4]);
        assert_eq!(v.false_eliminations, vec![4]);
        assert_eq!(v.worst_tied_rank, 3);
        assert_eq!(v.lines().len(), 5);
        let mut ex2 = ex.clone();
        ex2[4].error = Some(0.5);
        let v = validate(&race, &ex2).unwrap();
        assert!(v.winner_tied && v.winner_certified);
        assert!(v.false_eliminations.is_empty());
        // A race candidate missing from the exhaustive rows is an error.
        assert!(validate(&race, &ex[..3]).is_err());
    }
}
