//! [`JoinMemo`]: what a reader's last accepted cut lets it skip when joining the next.

use ygg_store::snapshot::{ArchivedManifest, ArchivedManifestLayer};

/// What the last cut a [`crate::SceneReader`] accepted lets it skip in the next one: per
/// manifest position, the layer's id, generation and node count. (Whether the structure
/// and the layer's segments are the ones accepted, the reader tells by their identities.)
#[derive(Debug, Default)]
pub(crate) struct JoinMemo {
    /// Per position in the last accepted manifest: `(layer id, generation, node count)`.
    /// A cut of the same structure lists the same layers at the same positions.
    layers: Vec<(u32, u64, u64)>,
}

impl JoinMemo {
    /// Whether a join may take the layer of manifest entry `entry`, at position `at` of a
    /// cut with the structure of the last accepted one (so the same parts), as checked,
    /// given that the caller found every one of its segments (parts, point and tree
    /// chunks) to be the very bytes of the last accepted cut: the layer had this id,
    /// generation and node count there.
    pub(crate) fn knows_layer(&self, at: usize, entry: &ArchivedManifestLayer) -> bool {
        self.layers.get(at) == Some(&key(entry))
    }

    /// Remembers an accepted cut's manifest.
    pub(crate) fn remember(&mut self, manifest: &ArchivedManifest) {
        self.layers.clear();
        self.layers.extend(manifest.layers.iter().map(key));
    }
}

/// What of a manifest entry a known layer must keep.
fn key(entry: &ArchivedManifestLayer) -> (u32, u64, u64) {
    (
        entry.id.to_native(),
        entry.generation.to_native(),
        entry.node_count.to_native(),
    )
}
