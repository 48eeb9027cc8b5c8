//! What a Python `Scene` holds: a validated snapshot (a mapped `.ygg` file, an in-memory
//! archive, a live scene's shared-memory samples, or a cut of a recording), its [`ArchivedScene`] view, and the
//! object catalog of the query contract, built once per snapshot.
//!
//! The view borrows the snapshot and the catalog borrows the view; `self_cell` ties each
//! to what it borrows, so no `unsafe` is needed. Both are immutable once built, and
//! every Python object that hands out data from a snapshot (a `Node`, a numpy array of
//! points, an `ObjectQueries`) holds an `Arc` of them, so the bytes stay mapped for as
//! long as any of them lives.

use std::sync::Arc;

use self_cell::self_cell;
use ygg_dsg::objects::Objects;
use ygg_reader::SceneSnapshot;
use ygg_store::recording::RecordedScene;
use ygg_store::{ArchivedScene, NodeId, SnapshotFile};

/// Where a snapshot's bytes live.
pub enum SnapshotSource {
    /// A `.ygg` file (memory-mapped) or an in-memory archive of a graph.
    File(SnapshotFile),
    /// A live scene's samples, held in shared memory until the last clone is dropped.
    Live(SceneSnapshot),
    /// A cut of a recording, queried in place on its mapped files.
    Recorded(RecordedScene),
}

impl SnapshotSource {
    /// The scene, queried in place.
    fn view(&self) -> ArchivedScene<'_> {
        match self {
            SnapshotSource::File(f) => f.view(),
            SnapshotSource::Live(s) => s.view().clone(),
            SnapshotSource::Recorded(s) => s.view().clone(),
        }
    }

    /// The snapshot generation (0 for a file).
    pub fn generation(&self) -> u64 {
        match self {
            SnapshotSource::File(_) => 0,
            SnapshotSource::Live(s) => s.generation(),
            SnapshotSource::Recorded(s) => s.summary().generation,
        }
    }
}

self_cell!(
    /// A snapshot and its [`ArchivedScene`] view.
    pub struct SnapshotView {
        owner: SnapshotSource,
        #[covariant]
        dependent: ArchivedScene,
    }
);

impl SnapshotView {
    /// Wraps a validated snapshot.
    pub fn open(source: SnapshotSource) -> Arc<Self> {
        Arc::new(SnapshotView::new(source, |s| s.view()))
    }

    /// The view every query runs on.
    pub fn view(&self) -> &ArchivedScene<'_> {
        self.borrow_dependent()
    }

    /// The snapshot generation (0 for a file).
    pub fn generation(&self) -> u64 {
        self.borrow_owner().generation()
    }
}

/// The object catalog over a snapshot's view.
pub type SceneObjects<'a> = Objects<'a, ArchivedScene<'a>>;

self_cell!(
    /// The object catalog ([`Objects`]) of a snapshot: the whole scene's, or one
    /// sub-tree's ([`Objects::in_subtree`]). Its lazily built caches are kept across
    /// queries.
    pub struct ObjectCatalog {
        owner: Arc<SnapshotView>,
        #[not_covariant]
        dependent: SceneObjects,
    }
);

impl ObjectCatalog {
    /// The catalog of every object of the snapshot.
    pub fn whole(view: Arc<SnapshotView>) -> Arc<Self> {
        Arc::new(ObjectCatalog::new(view, |v| Objects::new(v.view())))
    }

    /// The catalog of the objects in `root`'s sub-tree.
    pub fn subtree(view: Arc<SnapshotView>, root: NodeId) -> Arc<Self> {
        Arc::new(ObjectCatalog::new(view, |v| {
            Objects::in_subtree(v.view(), root)
        }))
    }
}
