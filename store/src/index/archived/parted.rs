//! [`PartedIndex`]: the layer index of a layer split into parts, as one index over the
//! parts' own layer indexes.

use super::kdtree::ArchivedIndex;
use crate::index::SpatialIndex;
use crate::snapshot::PART_ITEM_ROW_BITS;
use crate::{NodeId, Point};

/// The layer indexes of a layer's parts (each over its own rows) merged: a nearest search
/// visits every part under one shared bound, a radius search each part in turn. An item
/// is `place << PART_ITEM_ROW_BITS | row` for the part at `place`; for a layer in one
/// piece it is the row itself.
#[derive(Clone, Debug)]
pub struct PartedIndex<'a> {
    first: ArchivedIndex<'a>,
    rest: Vec<ArchivedIndex<'a>>,
}

impl<'a> PartedIndex<'a> {
    /// The index of a layer whose parts' indexes are `first` and `rest`, in order.
    ///
    /// # Invariant
    /// With more than one part, each part has fewer than `2^PART_ITEM_ROW_BITS` rows and
    /// there are fewer than `2^(32 - PART_ITEM_ROW_BITS)` parts (the join checks both).
    pub(crate) fn new(first: ArchivedIndex<'a>, rest: Vec<ArchivedIndex<'a>>) -> Self {
        PartedIndex { first, rest }
    }

    fn shift(&self) -> u32 {
        if self.rest.is_empty() {
            0
        } else {
            PART_ITEM_ROW_BITS
        }
    }

    fn parts(&self) -> impl Iterator<Item = (u32, &ArchivedIndex<'a>)> {
        std::iter::once(&self.first)
            .chain(&self.rest)
            .enumerate()
            .map(|(place, index)| (place as u32, index))
    }

    /// The part an item names and the item within it.
    fn split(&self, item: u32) -> Option<(&ArchivedIndex<'a>, u32)> {
        let shift = self.shift();
        if shift == 0 {
            return Some((&self.first, item));
        }
        let place = (item >> shift) as usize;
        let row = item & ((1 << shift) - 1);
        let index = if place == 0 {
            &self.first
        } else {
            self.rest.get(place - 1)?
        };
        Some((index, row))
    }
}

impl SpatialIndex for PartedIndex<'_> {
    fn len(&self) -> usize {
        self.parts().map(|(_, index)| index.len()).sum()
    }

    fn node_of(&self, item: u32) -> Option<NodeId> {
        let (index, row) = self.split(item)?;
        index.node_of(row)
    }

    fn prefetch_node(&self, item: u32) {
        if let Some((index, row)) = self.split(item) {
            index.prefetch_node(row);
        }
    }

    fn nearest_visit<F: FnMut(f32, u32) -> f32>(&self, c: &Point, mut f: F) {
        let shift = self.shift();
        if shift == 0 {
            return self.first.nearest_visit(c, f);
        }
        let mut bound = f32::INFINITY;
        for (place, index) in self.parts() {
            index.nearest_visit(c, |d2, row| {
                // A part's search starts unbounded: points beyond the shared bound are
                // not offered.
                if d2 <= bound {
                    bound = f(d2, place << shift | row);
                }
                bound
            });
        }
    }

    fn points_within<F: FnMut(f32, u32, &Point)>(&self, c: &Point, r2: f32, mut f: F) {
        let shift = self.shift();
        for (place, index) in self.parts() {
            index.points_within(c, r2, |d2, row, p| f(d2, place << shift | row, p));
        }
    }

    fn memory_bytes(&self) -> usize {
        self.parts().map(|(_, index)| index.memory_bytes()).sum()
    }
}
