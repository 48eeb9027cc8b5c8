//! [`JoinMemo`]: what a reader's last accepted cut lets it skip when joining the next.

use ygg_store::snapshot::{
    ArchivedManifest, ArchivedManifestLayer, CheckedManifest, chunk_segment_layer,
};

/// What the last cut a [`crate::SceneReader`] accepted lets it skip in the next one: its
/// manifest, whose structure was checked, and the layers that named no chunk, with the
/// generation and node count their entries had.
#[derive(Debug, Default)]
pub(crate) struct JoinMemo {
    manifest: Option<CheckedManifest>,
    /// `(layer id, generation, node count)` of each layer of the last accepted cut that
    /// named no point or tree chunk, ascending by id.
    plain_layers: Vec<(u32, u64, u64)>,
}

impl JoinMemo {
    /// `bytes` as a manifest without validating them again, if they have the structure of
    /// the last accepted cut's manifest (see [`CheckedManifest::same_structure`]).
    pub(crate) fn same_structure<'a>(&self, bytes: &'a [u8]) -> Option<&'a ArchivedManifest> {
        self.manifest.as_ref()?.same_structure(bytes)
    }

    /// Whether a join may take the layer of manifest entry `entry` as checked: its
    /// segment (id `segment_id`, bytes the caller found to be the same as in the last
    /// accepted cut) had this id, generation and node count there and named no chunk.
    pub(crate) fn knows_layer(&self, entry: &ArchivedManifestLayer, segment_id: u32) -> bool {
        let id = entry.id.to_native();
        id == segment_id
            && self
                .plain_layers
                .binary_search_by_key(&id, |l| l.0)
                .is_ok_and(|at| {
                    let (_, generation, nodes) = self.plain_layers[at];
                    generation == entry.generation.to_native()
                        && nodes == entry.node_count.to_native()
                })
    }

    /// Remembers an accepted cut: its manifest (read from `bytes`; copied unless its
    /// structure is the one remembered already) and the segment ids it listed.
    pub(crate) fn remember(
        &mut self,
        bytes: &[u8],
        manifest: &ArchivedManifest,
        same_structure: bool,
        segment_ids: impl Iterator<Item = u32>,
    ) {
        if !same_structure {
            self.manifest = Some(CheckedManifest::new(bytes, manifest));
        }
        let mut chunked: Vec<u32> = segment_ids
            .filter_map(|id| chunk_segment_layer(id).map(|l| l.0))
            .collect();
        chunked.sort_unstable();
        chunked.dedup();
        self.plain_layers.clear();
        self.plain_layers.extend(
            manifest
                .layers
                .iter()
                .filter(|m| chunked.binary_search(&m.id.to_native()).is_err())
                .map(|m| {
                    (
                        m.id.to_native(),
                        m.generation.to_native(),
                        m.node_count.to_native(),
                    )
                }),
        );
    }
}
