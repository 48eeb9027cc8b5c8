//! Timing: every query of the workload on every target, repeated, with per-family
//! median and p99.

use super::workload::{Answer, Query, Workload};
use std::collections::BTreeMap;
use std::time::Instant;
use ygg_testkit::stats::median_p99_us;

/// Something that answers workload queries (a rung of the ladder or an anchor).
pub trait Target {
    /// The target's name in the report.
    fn name(&self) -> String;
    /// Answers one query.
    fn answer(&self, q: &Query) -> Answer;
}

/// One timing row.
#[derive(Clone, Debug)]
pub struct Row {
    /// Target or anchor name.
    pub target: String,
    /// Query family ("Q1a", "Q1b@0.25", ...).
    pub query: String,
    /// Median latency, microseconds.
    pub median_us: f64,
    /// 99th-percentile latency, microseconds.
    pub p99_us: f64,
}

/// Queries per block of [`time_targets`].
const BLOCK: usize = 64;

/// Times every query `reps` times on every target; rows per target and family, targets
/// in the order given.
///
/// The targets take turns on blocks of [`BLOCK`] consecutive queries (each query
/// repeated `reps` times in a row, as a caller repeating a query would), so that load
/// from other processes drifting during the run hits every target alike and the ratios
/// between targets hold within one run.
pub fn time_targets(targets: &[&dyn Target], workload: &Workload, reps: usize) -> Vec<Row> {
    let mut samples: Vec<BTreeMap<String, Vec<f64>>> = vec![BTreeMap::new(); targets.len()];
    for block in workload.queries.chunks(BLOCK) {
        for (target, by_family) in targets.iter().zip(&mut samples) {
            for q in block {
                let s = by_family.entry(q.family()).or_default();
                for _ in 0..reps {
                    let t = Instant::now();
                    let a = target.answer(q);
                    let ns = t.elapsed().as_nanos() as f64;
                    std::hint::black_box(a);
                    s.push(ns);
                }
            }
        }
    }
    targets
        .iter()
        .zip(samples)
        .flat_map(|(target, by_family)| {
            let name = target.name();
            by_family.into_iter().map(move |(query, s)| {
                let (median_us, p99_us) = median_p99_us(&s);
                Row {
                    target: name.clone(),
                    query,
                    median_us,
                    p99_us,
                }
            })
        })
        .collect()
}

/// Answers of every query on every target; `Err` describes the first disagreement with
/// the first target.
pub fn compare_answers(
    targets: &[&dyn Target],
    workload: &Workload,
) -> Result<Vec<Answer>, String> {
    let Some((reference, rest)) = targets.split_first() else {
        return Ok(Vec::new());
    };
    let answers: Vec<Answer> = workload
        .queries
        .iter()
        .map(|q| reference.answer(q))
        .collect();
    for t in rest {
        for (i, (q, want)) in workload.queries.iter().zip(&answers).enumerate() {
            let got = t.answer(q);
            if &got != want {
                return Err(format!(
                    "query {i} ({q:?}): {} answers {want:?}, {} answers {got:?}",
                    reference.name(),
                    t.name()
                ));
            }
        }
    }
    Ok(answers)
}
