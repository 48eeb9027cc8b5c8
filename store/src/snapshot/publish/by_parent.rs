//! The rows-by-parent column of a layer segment ([`LayerSegment::by_parent`]): sorted
//! afresh for a full build, re-filed row by row for a patched one (appending a pose
//! nested under a place files one row).

use crate::snapshot::schema::{LayerSegment, NO_PARENT};

/// Past this many rows whose parent changed, a patched build sorts the column afresh.
const MAX_REFILED: usize = 64;

impl LayerSegment {
    /// Builds `by_parent` from the parent column: every row with a parent, ascending by
    /// (parent id, row).
    pub(crate) fn rebuild_by_parent(&mut self) {
        let parents = &self.parents;
        self.by_parent.clear();
        self.by_parent
            .extend((0..parents.len() as u32).filter(|&row| parents[row as usize] != NO_PARENT));
        self.by_parent
            .sort_unstable_by_key(|&row| (parents[row as usize], row));
    }

    /// Brings `by_parent` up to date with the parent column after a patched build.
    /// `rewritten` lists each row that build rewrote or appended with the parent it had
    /// before (`NO_PARENT` for an appended row); every other row kept its parent, and no
    /// row at or past the row count is listed in `by_parent`.
    pub(crate) fn refile_by_parent(&mut self, rewritten: &[(u32, u64)]) {
        let parents = &self.parents;
        let moved: Vec<(u32, u64)> = rewritten
            .iter()
            .copied()
            .filter(|&(row, was)| parents[row as usize] != was)
            .collect();
        if moved.len() > MAX_REFILED {
            return self.rebuild_by_parent();
        }
        let mut stale: Vec<u32> = moved
            .iter()
            .filter(|(_, was)| *was != NO_PARENT)
            .map(|(row, _)| *row)
            .collect();
        if !stale.is_empty() {
            stale.sort_unstable();
            self.by_parent
                .retain(|row| stale.binary_search(row).is_err());
        }
        for &(row, _) in &moved {
            let key = (parents[row as usize], row);
            if key.0 != NO_PARENT {
                let at = self
                    .by_parent
                    .partition_point(|&r| (parents[r as usize], r) < key);
                self.by_parent.insert(at, row);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::LayerId;

    fn segment(parents: &[u64]) -> LayerSegment {
        let mut s = LayerSegment::empty(LayerId(1), 1, "l", parents.len());
        s.parents = parents.to_vec();
        s.rebuild_by_parent();
        s
    }

    #[test]
    fn files_rows_by_parent_then_row() {
        let s = segment(&[7, NO_PARENT, 3, 7, 3]);
        assert_eq!(s.by_parent, [2, 4, 0, 3]);
    }

    #[test]
    fn refiling_equals_sorting_afresh() {
        let mut s = segment(&[7, NO_PARENT, 3, 7, 3]);
        // Row 0 moves to parent 1, row 2 loses its parent, row 1 gains one, rows 5
        // and 6 are appended (one nested, one not).
        let before = s.parents.clone();
        s.parents = vec![1, 9, NO_PARENT, 7, 3, 3, NO_PARENT];
        let rewritten: Vec<(u32, u64)> = [0u32, 1, 2]
            .iter()
            .map(|&r| (r, before[r as usize]))
            .chain([(5, NO_PARENT), (6, NO_PARENT)])
            .collect();
        s.refile_by_parent(&rewritten);
        let refiled = s.by_parent.clone();
        s.rebuild_by_parent();
        assert_eq!(refiled, s.by_parent);
        assert_eq!(refiled, [0, 4, 5, 3, 1]);
    }
}
