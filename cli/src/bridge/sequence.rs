//! Ordering a numbered stream of full and incremental updates (hydra_msgs' `DsgUpdate`
//! `sequence_number`): an incremental update applies only on top of the one numbered just
//! before it; after a gap (or any update that failed) the bridge waits for the next full
//! update, which always applies (a restarted sender counts again from 0).

/// What to do with a numbered update.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Verdict {
    /// Apply it.
    Apply,
    /// An incremental update numbered at or before the last one applied: a repeat.
    Stale,
    /// An incremental update after a missing one: `expected` is the number missing. The
    /// bridge now waits for a full update.
    Gap { expected: i64 },
    /// An incremental update while the bridge waits for a full update.
    WaitingForFull,
}

impl Verdict {
    /// The name in the bridge's `skipped` lines (none for [`Verdict::Apply`]).
    pub(super) fn name(self) -> &'static str {
        match self {
            Verdict::Apply => "apply",
            Verdict::Stale => "stale",
            Verdict::Gap { .. } => "gap",
            Verdict::WaitingForFull => "waiting-for-full-update",
        }
    }
}

/// Where a numbered stream stands.
#[derive(Debug, Default)]
pub(super) struct Sequence {
    /// The number the next incremental update must have; `None` until a full update
    /// applied, and again after a gap or a failure.
    next: Option<i64>,
}

impl Sequence {
    /// The verdict on an update numbered `number`, full or not. A gap forgets the base:
    /// every incremental update waits for the next full one.
    pub(super) fn admit(&mut self, number: i64, full: bool) -> Verdict {
        if full {
            return Verdict::Apply;
        }
        match self.next {
            None => Verdict::WaitingForFull,
            Some(n) if number < n => Verdict::Stale,
            Some(n) if number > n => {
                self.next = None;
                Verdict::Gap { expected: n }
            }
            Some(_) => Verdict::Apply,
        }
    }

    /// Records the outcome of an admitted update numbered `number`: the next incremental
    /// update follows it when it applied; none does when it failed.
    pub(super) fn applied(&mut self, number: i64, ok: bool) {
        self.next = ok.then(|| number.wrapping_add(1));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn incremental_updates_apply_in_order_and_a_gap_waits_for_a_full_update() {
        let mut s = Sequence::default();
        assert_eq!(s.admit(3, false), Verdict::WaitingForFull);
        assert_eq!(s.admit(4, true), Verdict::Apply);
        s.applied(4, true);
        assert_eq!(s.admit(5, false), Verdict::Apply);
        s.applied(5, true);
        assert_eq!(s.admit(5, false), Verdict::Stale);
        assert_eq!(s.admit(7, false), Verdict::Gap { expected: 6 });
        assert_eq!(s.admit(8, false), Verdict::WaitingForFull);
        assert_eq!(s.admit(9, true), Verdict::Apply);
        s.applied(9, true);
        assert_eq!(s.admit(10, false), Verdict::Apply);
        // A failed update breaks the chain too.
        s.applied(10, false);
        assert_eq!(s.admit(11, false), Verdict::WaitingForFull);
        // A restarted sender's full update applies whatever its number.
        assert_eq!(s.admit(0, true), Verdict::Apply);
        s.applied(0, true);
        assert_eq!(s.admit(1, false), Verdict::Apply);
    }
}
