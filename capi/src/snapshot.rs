//! The snapshot handle (`ygg_snapshot`): a validated, immutable cut of a scene (from a
//! reader, a `.ygg` file, a graph or a recording), and its node accessors.
//!
//! Pointers the accessors return (points, strings) point into the snapshot's
//! mapped bytes: zero-copy, valid while the snapshot handle lives, never to be freed or
//! written by the caller.
//!
//! Thread-safety of `ygg_snapshot`: immutable, so any number of threads may call its
//! accessors and queries at once; destroy it only when no thread uses it.

use crate::args::{Out, str_arg};
use crate::errors::{FfiError, FfiResult, YggStatus, guard};
use crate::graph::graph_arg;
use crate::handle::{self, Handle, Kind};
use crate::lists::{YggNodeList, deliver_ids};
use self_cell::self_cell;
use std::collections::HashMap;
use std::ffi::c_char;
use std::sync::Mutex;
use ygg_dsg::objects::Objects;
use ygg_reader::SceneSnapshot;
use ygg_store::recording::RecordedScene;
use ygg_store::{ArchivedScene, FeatureRef, LayerId, NodeId, Point, SceneView, SnapshotFile};

/// A validated snapshot of a scene, with its view and object catalog built once.
///
/// Thread-safety: immutable; any number of threads may query it at once. Destroy it only
/// when no thread uses it (pointers its accessors returned die with it).
pub struct YggSnapshot {
    catalog: SnapshotCatalog,
    /// Points of nodes that lie in two or more chunks of a chunked layer, copied into
    /// one piece on first request and kept for the handle's life (so the pointer
    /// `ygg_snapshot_node_points` hands out stays valid as long as the snapshot).
    joined_points: Mutex<HashMap<u64, Box<[Point]>>>,
}

/// Where a snapshot's bytes live.
enum SnapshotSource {
    /// Shared-memory samples received by a reader (or their private copies).
    Live(SceneSnapshot),
    /// A mapped `.ygg` file, or a graph archived in memory.
    File(SnapshotFile),
    /// A cut of a recording, on its mapped files.
    Recorded(RecordedScene),
}

self_cell!(
    /// A snapshot's bytes and the [`ArchivedScene`] view over them, built once.
    struct SnapshotView {
        owner: SnapshotSource,
        #[covariant]
        dependent: ArchivedScene,
    }
);

/// The object catalog over a snapshot's view.
type SceneObjects<'a> = Objects<'a, ArchivedScene<'a>>;

self_cell!(
    /// A snapshot's view and its object catalog ([`Objects`]), whose lazily built caches
    /// are kept across queries (the view and catalog are built once per handle, not per
    /// call).
    struct SnapshotCatalog {
        owner: SnapshotView,
        #[not_covariant]
        dependent: SceneObjects,
    }
);

impl Handle for YggSnapshot {
    const KIND: Kind = Kind::Snapshot;
    const NAME: &'static str = "snapshot";
}

// Queries on one snapshot from several threads at once are part of the contract.
const _: fn() = || {
    fn shareable<T: Send + Sync>() {}
    shareable::<YggSnapshot>();
};

impl YggSnapshot {
    /// A snapshot a reader received.
    pub(crate) fn live(snapshot: SceneSnapshot) -> Self {
        YggSnapshot::new(SnapshotSource::Live(snapshot))
    }

    /// A cut of a recording.
    pub(crate) fn recorded(scene: RecordedScene) -> Self {
        YggSnapshot::new(SnapshotSource::Recorded(scene))
    }

    fn new(source: SnapshotSource) -> Self {
        let view = SnapshotView::new(source, |source| match source {
            SnapshotSource::Live(s) => s.view().clone(),
            SnapshotSource::File(f) => f.view(),
            SnapshotSource::Recorded(r) => r.view().clone(),
        });
        YggSnapshot {
            catalog: SnapshotCatalog::new(view, |view| Objects::new(view.borrow_dependent())),
            joined_points: Mutex::default(),
        }
    }

    /// The scene as a view over the snapshot's bytes (every store query runs on it).
    pub(crate) fn view(&self) -> &ArchivedScene<'_> {
        self.catalog.borrow_owner().borrow_dependent()
    }

    /// Runs `f` on the snapshot's object catalog (the object contract's queries).
    pub(crate) fn with_objects<T>(&self, f: impl FnOnce(&SceneObjects<'_>) -> T) -> T {
        self.catalog.with_dependent(|_, objects| f(objects))
    }
}

/// The snapshot handle argument.
pub(crate) fn snapshot_arg<'a>(snapshot: *const YggSnapshot) -> FfiResult<&'a YggSnapshot> {
    handle::resolve(snapshot, "snapshot")
}

/// The view of a snapshot handle argument.
pub(crate) fn view_arg<'a>(snapshot: *const YggSnapshot) -> FfiResult<&'a ArchivedScene<'a>> {
    Ok(snapshot_arg(snapshot)?.view())
}

/// The node `id` of `view`, or `YGG_STATUS_NOT_FOUND`.
fn node_arg<'v>(
    view: &'v ArchivedScene<'_>,
    id: u64,
) -> FfiResult<<ArchivedScene<'v> as SceneView>::NodeRef<'v>> {
    view.node(NodeId(id))
        .ok_or_else(|| FfiError::new(YggStatus::NotFound, format!("no node {id} in the snapshot")))
}

/// A feature's kind (the `kind` field of `ygg_feature`).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum YggFeatureKind {
    /// `str` and `str_len` hold it.
    Str = 0,
    /// `int_value` holds it.
    Int = 1,
    /// `float_value` holds it.
    Float = 2,
    /// `bool_value` holds it.
    Bool = 3,
}

/// A feature value read from a snapshot; only the field its `kind` names is set.
///
/// Ownership: `str` points into the snapshot's bytes (not NUL-terminated; `str_len`
/// bytes of UTF-8), valid while the snapshot handle lives.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct YggFeature {
    /// Which field holds the value.
    pub kind: YggFeatureKind,
    /// The integer value.
    pub int_value: i64,
    /// The float value.
    pub float_value: f64,
    /// The boolean value.
    pub bool_value: bool,
    /// The string value (not NUL-terminated), or null.
    pub str: *const c_char,
    /// Its length in bytes.
    pub str_len: usize,
}

impl From<FeatureRef<'_>> for YggFeature {
    fn from(value: FeatureRef<'_>) -> Self {
        let mut out = YggFeature {
            kind: YggFeatureKind::Int,
            int_value: 0,
            float_value: 0.0,
            bool_value: false,
            str: std::ptr::null(),
            str_len: 0,
        };
        match value {
            FeatureRef::Str(s) => {
                out.kind = YggFeatureKind::Str;
                out.str = s.as_ptr().cast();
                out.str_len = s.len();
            }
            FeatureRef::Int(v) => out.int_value = v,
            FeatureRef::Float(v) => {
                out.kind = YggFeatureKind::Float;
                out.float_value = v;
            }
            FeatureRef::Bool(v) => {
                out.kind = YggFeatureKind::Bool;
                out.bool_value = v;
            }
        }
        out
    }
}

/// Opens a `.ygg` snapshot file: maps it and validates it once.
///
/// Ownership: `*out` receives a new snapshot handle the caller destroys with
/// `ygg_snapshot_destroy`.
///
/// # Safety
/// `path` is null or NUL-terminated; `out` is null or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_snapshot_open_file(
    path: *const c_char,
    out: *mut *mut YggSnapshot,
) -> YggStatus {
    guard("ygg_snapshot_open_file", || {
        // SAFETY: the caller's contract for `path` and `out`.
        let (path, out) = unsafe { (str_arg(path, "path")?, Out::new(out, "out")?) };
        let file = SnapshotFile::open(path).map_err(FfiError::wrap(YggStatus::Io, "open"))?;
        out.write(handle::register(YggSnapshot::new(SnapshotSource::File(
            file,
        ))));
        Ok(())
    })
}

/// Archives a graph into an in-memory snapshot (the bytes a `.ygg` file would hold), to
/// query it exactly as a reader would. The snapshot does not follow later mutations.
///
/// Ownership: `*out` receives a new snapshot handle the caller destroys.
///
/// # Safety
/// `out` is null or writable; `graph` is not used by another thread during the call.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_graph_snapshot(
    graph: *mut crate::graph::YggGraph,
    out: *mut *mut YggSnapshot,
) -> YggStatus {
    guard("ygg_graph_snapshot", || {
        // SAFETY: the caller's contract for `out`.
        let out = unsafe { Out::new(out, "out") }?;
        let file = graph_arg(graph)?.to_snapshot();
        out.write(handle::register(YggSnapshot::new(SnapshotSource::File(
            file,
        ))));
        Ok(())
    })
}

/// Destroys a snapshot; pointers its accessors returned become invalid.
///
/// # Safety
/// No other thread uses `snapshot` during or after the call.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_snapshot_destroy(snapshot: *mut YggSnapshot) -> YggStatus {
    guard("ygg_snapshot_destroy", || {
        drop(handle::unregister(snapshot, "snapshot")?);
        Ok(())
    })
}

/// The snapshot's generation (the writer's publish count; 0 for files and graphs).
///
/// # Safety
/// `generation` is null or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_snapshot_generation(
    snapshot: *const YggSnapshot,
    generation: *mut u64,
) -> YggStatus {
    guard("ygg_snapshot_generation", || {
        // SAFETY: the caller's contract for `generation`.
        let out = unsafe { Out::new(generation, "generation") }?;
        out.write(view_arg(snapshot)?.generation());
        Ok(())
    })
}

/// The number of nodes.
///
/// # Safety
/// `count` is null or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_snapshot_node_count(
    snapshot: *const YggSnapshot,
    count: *mut usize,
) -> YggStatus {
    guard("ygg_snapshot_node_count", || {
        // SAFETY: the caller's contract for `count`.
        let out = unsafe { Out::new(count, "count") }?;
        out.write(view_arg(snapshot)?.node_count());
        Ok(())
    })
}

/// The id of the layer named `name` (`YGG_STATUS_NOT_FOUND` if none).
///
/// # Safety
/// `name` is null or NUL-terminated; `layer` is null or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_snapshot_layer_by_name(
    snapshot: *const YggSnapshot,
    name: *const c_char,
    layer: *mut u32,
) -> YggStatus {
    guard("ygg_snapshot_layer_by_name", || {
        // SAFETY: the caller's contract for `name` and `layer`.
        let (name, out) = unsafe { (str_arg(name, "name")?, Out::new(layer, "layer")?) };
        let id = view_arg(snapshot)?.layer_by_name(name).ok_or_else(|| {
            FfiError::new(YggStatus::NotFound, format!("no layer named {name:?}"))
        })?;
        out.write(id.0);
        Ok(())
    })
}

/// The nodes of a layer, ascending (`YGG_STATUS_NOT_FOUND` for an unknown layer).
///
/// Ownership: `*list` is overwritten (not freed) with a list the caller frees with
/// `ygg_node_list_free`; on error it is the empty list.
///
/// # Safety
/// `list` is null or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_snapshot_layer_nodes(
    snapshot: *const YggSnapshot,
    layer: u32,
    list: *mut YggNodeList,
) -> YggStatus {
    guard("ygg_snapshot_layer_nodes", || {
        // SAFETY: the caller's contract for `list`.
        let out = unsafe { Out::new(list, "list") }?;
        let view = view_arg(snapshot);
        let found = view.and_then(|view| {
            if view.layer_name(LayerId(layer)).is_none() {
                return Err(FfiError::new(
                    YggStatus::NotFound,
                    format!("no layer {layer}"),
                ));
            }
            let mut ids: Vec<NodeId> = view
                .layer_nodes(LayerId(layer))
                .map(|n| view.node_id(n))
                .collect();
            ids.sort_unstable();
            Ok(ids)
        });
        deliver_ids(found, out)
    })
}

/// A node's layer.
///
/// # Safety
/// `layer` is null or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_snapshot_node_layer(
    snapshot: *const YggSnapshot,
    node: u64,
    layer: *mut u32,
) -> YggStatus {
    guard("ygg_snapshot_node_layer", || {
        // SAFETY: the caller's contract for `layer`.
        let out = unsafe { Out::new(layer, "layer") }?;
        let view = view_arg(snapshot)?;
        out.write(view.node_layer(node_arg(view, node)?).0);
        Ok(())
    })
}

/// A node's geometry: `*xyz` points to `3 * *count` floats (x y z of each point), null
/// when the node has no points. Zero-copy (the snapshot's bytes) unless the node's points
/// cross a chunk boundary of a chunked layer (a mesh node of more than 32,768 points by default): then
/// a copy in one piece, made once and owned by the snapshot.
///
/// Ownership: the points belong to the snapshot: valid while the snapshot handle lives;
/// do not free or write them.
///
/// # Safety
/// `xyz` and `count` are null or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_snapshot_node_points(
    snapshot: *const YggSnapshot,
    node: u64,
    xyz: *mut *const f32,
    count: *mut usize,
) -> YggStatus {
    guard("ygg_snapshot_node_points", || {
        // SAFETY: the caller's contract for `xyz` and `count`.
        let (xyz, count) = unsafe { (Out::new(xyz, "xyz")?, Out::new(count, "count")?) };
        let handle = handle::resolve(snapshot, "snapshot")?;
        let view = handle.view();
        let points = view.points(node_arg(view, node)?);
        let first = match points.as_slice() {
            // The slice lies in the snapshot's segment bytes, which the handle keeps mapped.
            Some(one) => one.as_ptr(),
            None => {
                let mut joined = handle
                    .joined_points
                    .lock()
                    .unwrap_or_else(|poisoned| poisoned.into_inner());
                // The boxed copy lives, unmoved, as long as the handle.
                joined
                    .entry(node)
                    .or_insert_with(|| points.to_vec().into_boxed_slice())
                    .as_ptr()
            }
        };
        xyz.write(if points.is_empty() {
            std::ptr::null()
        } else {
            first.cast()
        });
        count.write(points.len());
        Ok(())
    })
}

/// A node's parent: `*has_parent` says whether it has one, `*parent` is its id (0 when
/// none).
///
/// # Safety
/// `has_parent` and `parent` are null or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_snapshot_node_parent(
    snapshot: *const YggSnapshot,
    node: u64,
    has_parent: *mut bool,
    parent: *mut u64,
) -> YggStatus {
    guard("ygg_snapshot_node_parent", || {
        // SAFETY: the caller's contract for `has_parent` and `parent`.
        let (has, out) = unsafe {
            (
                Out::new(has_parent, "has_parent")?,
                Out::new(parent, "parent")?,
            )
        };
        let view = view_arg(snapshot)?;
        let p = view.parent(node_arg(view, node)?);
        has.write(p.is_some());
        out.write(p.map_or(0, |p| p.0));
        Ok(())
    })
}

/// A node's children, ascending (`YGG_STATUS_NOT_FOUND` for an unknown node). They are
/// gathered from the layers below the node's (a snapshot keeps nesting on the child's
/// side), so they come as a list, not a pointer into the snapshot.
///
/// Ownership: as `ygg_snapshot_layer_nodes`.
///
/// # Safety
/// `list` is null or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_snapshot_node_children(
    snapshot: *const YggSnapshot,
    node: u64,
    list: *mut YggNodeList,
) -> YggStatus {
    guard("ygg_snapshot_node_children", || {
        // SAFETY: the caller's contract for `list`.
        let out = unsafe { Out::new(list, "list") }?;
        let found =
            view_arg(snapshot).and_then(|view| Ok(view.children(node_arg(view, node)?).collect()));
        deliver_ids(found, out)
    })
}

/// A node's bounding box (min x y z, max x y z) if it keeps one and its sub-tree has a
/// point: `*has_box` says whether `box6` was written.
///
/// # Safety
/// `has_box` is null or writable; `box6` is null or holds 6 writable floats.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_snapshot_node_aabb(
    snapshot: *const YggSnapshot,
    node: u64,
    has_box: *mut bool,
    box6: *mut f32,
) -> YggStatus {
    guard("ygg_snapshot_node_aabb", || {
        // SAFETY: the caller's contract: `has_box` one bool, `box6` six floats.
        let (has, out) = unsafe {
            (
                Out::new(has_box, "has_box")?,
                Out::new(box6.cast::<[f32; 6]>(), "box6")?,
            )
        };
        let view = view_arg(snapshot)?;
        let b = view.aabb(node_arg(view, node)?);
        has.write(b.is_some());
        if let Some(b) = b {
            out.write(b.to_array());
        }
        Ok(())
    })
}

/// Whether a node carries `label`.
///
/// # Safety
/// `label` is null or NUL-terminated; `has_label` is null or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_snapshot_node_has_label(
    snapshot: *const YggSnapshot,
    node: u64,
    label: *const c_char,
    has_label: *mut bool,
) -> YggStatus {
    guard("ygg_snapshot_node_has_label", || {
        // SAFETY: the caller's contract for `label` and `has_label`.
        let (label, out) = unsafe { (str_arg(label, "label")?, Out::new(has_label, "has_label")?) };
        let view = view_arg(snapshot)?;
        out.write(view.has_label(node_arg(view, node)?, label));
        Ok(())
    })
}

/// How many labels a node carries (read them with `ygg_snapshot_node_label`).
///
/// # Safety
/// `count` is null or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_snapshot_node_label_count(
    snapshot: *const YggSnapshot,
    node: u64,
    count: *mut usize,
) -> YggStatus {
    guard("ygg_snapshot_node_label_count", || {
        // SAFETY: the caller's contract for `count`.
        let out = unsafe { Out::new(count, "count") }?;
        let view = view_arg(snapshot)?;
        out.write(view.labels(node_arg(view, node)?).count());
        Ok(())
    })
}

/// A node's label number `index` (`0 <= index < label count`; the order is fixed for a
/// snapshot): `*label` points to `*len` bytes of UTF-8, not NUL-terminated.
///
/// Ownership: as `ygg_snapshot_node_points`.
///
/// # Safety
/// `label` and `len` are null or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_snapshot_node_label(
    snapshot: *const YggSnapshot,
    node: u64,
    index: usize,
    label: *mut *const c_char,
    len: *mut usize,
) -> YggStatus {
    guard("ygg_snapshot_node_label", || {
        // SAFETY: the caller's contract for `label` and `len`.
        let (label, len) = unsafe { (Out::new(label, "label")?, Out::new(len, "len")?) };
        let view = view_arg(snapshot)?;
        let text = view
            .labels(node_arg(view, node)?)
            .nth(index)
            .ok_or_else(|| {
                FfiError::new(
                    YggStatus::NotFound,
                    format!("node {node} has no label number {index}"),
                )
            })?;
        label.write(text.as_ptr().cast());
        len.write(text.len());
        Ok(())
    })
}

/// A node's feature `key` (`YGG_STATUS_NOT_FOUND` when it has none).
///
/// Ownership: a string value points into the snapshot (see `ygg_feature`).
///
/// # Safety
/// `key` is null or NUL-terminated; `feature` is null or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_snapshot_node_feature(
    snapshot: *const YggSnapshot,
    node: u64,
    key: *const c_char,
    feature: *mut YggFeature,
) -> YggStatus {
    guard("ygg_snapshot_node_feature", || {
        // SAFETY: the caller's contract for `key` and `feature`.
        let (key, out) = unsafe { (str_arg(key, "key")?, Out::new(feature, "feature")?) };
        let view = view_arg(snapshot)?;
        let value = view.feature(node_arg(view, node)?, key).ok_or_else(|| {
            FfiError::new(
                YggStatus::NotFound,
                format!("node {node} has no feature {key:?}"),
            )
        })?;
        out.write(YggFeature::from(value));
        Ok(())
    })
}
