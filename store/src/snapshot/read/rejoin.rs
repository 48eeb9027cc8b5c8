//! Joining a reader's next cut without checking again what it checked in the last one:
//! [`KnownParts`] (what of a cut [`super::ArchivedScene::rejoin`] may take as checked).

/// What [`super::ArchivedScene::rejoin`] may take as checked, because the same reader
/// joined it in an earlier cut.
#[derive(Debug, Clone, Copy, Default)]
pub struct KnownParts<'k> {
    /// The structure segment is the very bytes of one a join accepted: ascending layer
    /// ids, DAG, names, part lists and term lists need no check.
    pub structure: bool,
    /// Per layer position in the manifest: `true` if every part of the layer and every
    /// point and tree chunk given for it is the very bytes of an earlier accepted cut, the
    /// same segments as there, and its manifest entry has the generation and node count it
    /// had there. Shorter than the layer count: the rest are unknown.
    pub layers: &'k [bool],
}

impl KnownParts<'_> {
    /// Nothing known: a join checks everything.
    pub const NONE: KnownParts<'static> = KnownParts {
        structure: false,
        layers: &[],
    };

    /// Whether the layer at manifest position `i` is known.
    pub(super) fn layer(&self, i: usize) -> bool {
        self.layers.get(i).copied().unwrap_or(false)
    }
}
