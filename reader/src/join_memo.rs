//! [`JoinMemo`]: what a reader's last accepted cut lets it skip when joining the next.

use ygg_store::snapshot::{ArchivedManifest, ArchivedManifestLayer, chunk_segment_layer};

/// What the last cut a [`crate::SceneReader`] accepted lets it skip in the next one: per
/// manifest position, the layer's id, generation and node count if it named no chunk.
/// (Whether the structure is the one accepted, the reader tells by the structure
/// segment's identity.)
#[derive(Debug, Default)]
pub(crate) struct JoinMemo {
    /// Per position in the last accepted manifest: `(layer id, generation, node count)`
    /// of a layer that named no point or tree chunk, `None` for one that did. A cut of the
    /// same structure lists the same layers at the same positions.
    plain_layers: Vec<Option<(u32, u64, u64)>>,
}

impl JoinMemo {
    /// Whether a join may take the layer of manifest entry `entry`, at position `at` of a
    /// cut with the structure of the last accepted one (so the same parts), as checked,
    /// given that the caller found every part's bytes to be the same as in the last
    /// accepted cut: the layer had this id, generation and node count there and named no
    /// chunk.
    pub(crate) fn knows_layer(&self, at: usize, entry: &ArchivedManifestLayer) -> bool {
        let now = (
            entry.id.to_native(),
            entry.generation.to_native(),
            entry.node_count.to_native(),
        );
        self.plain_layers.get(at) == Some(&Some(now))
    }

    /// Remembers an accepted cut: its manifest and the segment ids it listed.
    pub(crate) fn remember(
        &mut self,
        manifest: &ArchivedManifest,
        segment_ids: impl Iterator<Item = u64>,
    ) {
        let mut chunked: Vec<u32> = segment_ids
            .filter_map(|id| chunk_segment_layer(id).map(|l| l.0))
            .collect();
        chunked.sort_unstable();
        chunked.dedup();
        // Both ascend by id: one walk.
        let mut chunked = chunked.into_iter().peekable();
        self.plain_layers.clear();
        self.plain_layers.extend(manifest.layers.iter().map(|m| {
            let id = m.id.to_native();
            while chunked.next_if(|&c| c < id).is_some() {}
            chunked
                .next_if_eq(&id)
                .is_none()
                .then(|| (id, m.generation.to_native(), m.node_count.to_native()))
        }));
    }
}
