//! [`TouchLog`]: which layers changed after a given point, so that a publisher finds the
//! changed layers in O(changed), not by looking at every layer of a large building (the
//! graph's API over it: [`crate::SceneGraph::touch_mark`],
//! [`crate::SceneGraph::layers_touched_since`]).

use crate::LayerId;
use rustc_hash::FxHashSet;
use std::sync::atomic::{AtomicU64, Ordering};

/// A point in a graph's history of layer changes ([`crate::SceneGraph::touch_mark`]):
/// [`crate::SceneGraph::layers_touched_since`] reports every layer changed after it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TouchMark {
    /// The log it came from: a mark of another graph (or of a clone) reports nothing.
    origin: u64,
    sequence: u64,
}

/// Gives every log its own origin.
static NEXT_ORIGIN: AtomicU64 = AtomicU64::new(1);

/// Fewest entries the log holds before it is compacted, whatever the number of layers.
const MIN_COMPACT: usize = 4096;

/// The layers changed, in the order of their last change: `(sequence, layer)`,
/// ascending by sequence; a layer may appear more than once until the log is compacted
/// to its last entry per layer (amortised O(1) per change).
#[derive(Debug)]
pub(crate) struct TouchLog {
    origin: u64,
    sequence: u64,
    entries: Vec<(u64, LayerId)>,
    /// Entries left by the last compaction (the next one waits for twice as many).
    compacted: usize,
}

impl Default for TouchLog {
    fn default() -> Self {
        TouchLog {
            origin: NEXT_ORIGIN.fetch_add(1, Ordering::Relaxed),
            sequence: 0,
            entries: Vec::new(),
            compacted: 0,
        }
    }
}

/// A clone is another graph: its marks are its own.
impl Clone for TouchLog {
    fn clone(&self) -> Self {
        TouchLog {
            sequence: self.sequence,
            entries: self.entries.clone(),
            compacted: self.compacted,
            ..TouchLog::default()
        }
    }
}

impl TouchLog {
    /// Notes a change of `layer`.
    pub(crate) fn touch(&mut self, layer: LayerId) {
        self.sequence += 1;
        match self.entries.last_mut() {
            // The same layer again (a pose gets a node, its points, a feature...).
            Some(last) if last.1 == layer => last.0 = self.sequence,
            _ => {
                self.entries.push((self.sequence, layer));
                if self.entries.len() > MIN_COMPACT.max(2 * self.compacted) {
                    self.compact();
                }
            }
        }
    }

    /// Drops a removed layer's entries.
    pub(crate) fn forget(&mut self, layer: LayerId) {
        self.entries.retain(|e| e.1 != layer);
    }

    /// Keeps only the last entry of each layer.
    fn compact(&mut self) {
        let mut seen = FxHashSet::default();
        let mut kept: Vec<(u64, LayerId)> = self
            .entries
            .iter()
            .rev()
            .filter(|e| seen.insert(e.1))
            .copied()
            .collect();
        kept.reverse();
        self.compacted = kept.len();
        self.entries = kept;
    }

    /// The point after the last change so far.
    pub(crate) fn mark(&self) -> TouchMark {
        TouchMark {
            origin: self.origin,
            sequence: self.sequence,
        }
    }

    /// The layers changed after `mark`, ascending, each once (removed layers are not
    /// listed); `None` for a mark of another log.
    pub(crate) fn touched_since(&self, mark: TouchMark) -> Option<Vec<LayerId>> {
        if mark.origin != self.origin {
            return None;
        }
        let start = self.entries.partition_point(|e| e.0 <= mark.sequence);
        let mut layers: Vec<LayerId> = self.entries[start..].iter().map(|e| e.1).collect();
        layers.sort_unstable();
        layers.dedup();
        Some(layers)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reports_each_layer_changed_after_a_mark_across_compactions() {
        let mut log = TouchLog::default();
        log.touch(LayerId(3));
        let first = log.mark();
        assert_eq!(log.touched_since(first), Some(Vec::new()));
        for i in 0..20_000u32 {
            log.touch(LayerId(i % 7));
        }
        let second = log.mark();
        log.touch(LayerId(5));
        log.touch(LayerId(5));
        log.touch(LayerId(2));
        let since = |mark| log.touched_since(mark).unwrap();
        assert_eq!(since(first), (0..7).map(LayerId).collect::<Vec<_>>());
        assert_eq!(since(second), [LayerId(2), LayerId(5)]);
        assert!(
            log.entries.len() <= 2 * MIN_COMPACT,
            "compacted: {}",
            log.entries.len()
        );
        log.forget(LayerId(5));
        assert_eq!(log.touched_since(second).unwrap(), [LayerId(2)]);
        // A clone keeps the entries but not the marks: its changes are its own.
        let clone = log.clone();
        assert_eq!(clone.touched_since(second), None);
        assert_eq!(clone.touched_since(clone.mark()), Some(Vec::new()));
    }
}
