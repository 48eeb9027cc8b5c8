//! [`AnswerLine`]: what a reader process in q1a mode prints for each snapshot, the protocol
//! between the ladder's writer ([`super::after_ipc`]) and `ygg-bench ipc reader --mode
//! q1a`.

use super::workload::Answer;
use std::fmt;
use std::str::FromStr;
use ygg_store::{NodeId, SceneView};

/// First word of a reader's answer line.
pub const TAG: &str = "q1a";

/// One answer of a reader in q1a mode:
/// `q1a <generation> <visible ns> <answered ns> <ids> <mesh checksum>`, the ids
/// comma-separated (`-` for none).
#[derive(Clone, Debug, PartialEq)]
pub struct AnswerLine {
    /// Generation of the snapshot the query ran on.
    pub generation: u64,
    /// Unix ns when the reader held the snapshot's view.
    pub visible_ns: u64,
    /// Unix ns when the reader had the answer.
    pub answered_ns: u64,
    /// The answer (sorted object ids).
    pub ids: Answer,
    /// [`mesh_checksum`] of the moved object in the snapshot.
    pub mesh_checksum: f64,
}

/// A checksum of `object`'s mesh in `view`: the sum of every coordinate of its mesh
/// nodes (ids ascending), in f64, so the same points give the same bits in the writer's
/// live graph and in a reader's snapshot.
pub fn mesh_checksum<V: SceneView>(view: &V, object: NodeId) -> f64 {
    let mut mesh = ygg_store::query::children(view, object);
    mesh.sort_unstable();
    mesh.iter()
        .filter_map(|&m| view.node(m))
        .flat_map(|n| view.points(n))
        .flatten()
        .map(|&c| f64::from(c))
        .sum()
}

impl fmt::Display for AnswerLine {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{TAG} {} {} {} ",
            self.generation, self.visible_ns, self.answered_ns
        )?;
        if self.ids.is_empty() {
            f.write_str("-")?;
        }
        for (i, id) in self.ids.iter().enumerate() {
            if i > 0 {
                f.write_str(",")?;
            }
            write!(f, "{id}")?;
        }
        write!(f, " {}", self.mesh_checksum)
    }
}

impl FromStr for AnswerLine {
    type Err = String;

    fn from_str(line: &str) -> Result<Self, String> {
        let bad = || format!("malformed answer line {line:?}");
        let words: Vec<&str> = line.split_whitespace().collect();
        let [TAG, generation, visible, answered, ids, checksum] = words[..] else {
            return Err(bad());
        };
        let number = |s: &str| s.parse::<u64>().map_err(|_| bad());
        let ids = match ids {
            "-" => Vec::new(),
            list => list.split(',').map(number).collect::<Result<_, _>>()?,
        };
        Ok(AnswerLine {
            generation: number(generation)?,
            visible_ns: number(visible)?,
            answered_ns: number(answered)?,
            ids,
            mesh_checksum: checksum.parse().map_err(|_| bad())?,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn answer_lines_round_trip() {
        for ids in [vec![], vec![7], vec![3, 5_692_549_928_996_306_947]] {
            let line = AnswerLine {
                generation: 12,
                visible_ns: 1_700_000_000_000_000_000,
                answered_ns: 1_700_000_000_000_004_321,
                ids,
                mesh_checksum: -1_234.567_890_123_4,
            };
            assert_eq!(line.to_string().parse::<AnswerLine>(), Ok(line));
        }
        assert_eq!(
            "q1a 4 10 20 - 0.5".parse::<AnswerLine>().map(|l| l.ids),
            Ok(vec![])
        );
    }

    #[test]
    fn malformed_answer_lines_are_rejected() {
        for line in [
            "",
            "q1a 4 10 20 1",
            "q1a 4 10 20 1,2 0.5 extra",
            "seen 4 10 20 1 0.5",
            "q1a 4 10 x 1 0.5",
            "q1a 4 10 20 1,,2 0.5",
            "q1a -4 10 20 1 0.5",
            "q1a 4 10 20 1 x",
        ] {
            assert!(line.parse::<AnswerLine>().is_err(), "{line:?} parsed");
        }
    }
}
