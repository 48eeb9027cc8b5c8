//! The graph handle (`ygg_graph`): building and mutating a scene graph, saving `.ygg`
//! files and importing Spark-DSG files.
//!
//! Thread-safety of `ygg_graph`: not thread-safe. Use one graph from one thread at a time
//! (it may move between threads); the library does no locking of its own.

use crate::args::{Out, points_arg, str_arg};
use crate::errors::{FfiError, FfiResult, YggStatus, guard};
use crate::handle::{self, Handle, Kind};
use std::ffi::c_char;
use std::ptr::NonNull;
use ygg_dsg::layout::{self, Layout};
use ygg_dsg::{ImportOptions, read_file_with};
use ygg_store::{EditResult, FeatureValue, LayerId, NodeId, SceneGraph};
use ygg_writer::SceneWriter;

/// A scene graph being built: owned by the caller (`ygg_graph_create`,
/// `ygg_graph_import_dsg`), or the live graph of a writer (`ygg_writer_graph`).
///
/// Thread-safety: not thread-safe. Use a graph from one thread at a time (it may move
/// between threads); a writer's graph counts as part of its writer.
pub struct YggGraph {
    slot: GraphSlot,
}

/// Where the graph lives.
#[expect(
    clippy::large_enum_variant,
    reason = "one per handle, and the handle is boxed already"
)]
enum GraphSlot {
    /// The handle owns it.
    Owned(SceneGraph),
    /// It is a writer's live graph; the handle is destroyed with the writer.
    OfWriter(NonNull<SceneWriter>),
}

impl Handle for YggGraph {
    const KIND: Kind = Kind::Graph;
    const NAME: &'static str = "graph";
}

impl YggGraph {
    /// A handle to the live graph of `writer`, the scene writer inside a writer handle
    /// (registered by that handle, and destroyed before it).
    pub(crate) fn of_writer(writer: NonNull<SceneWriter>) -> Self {
        YggGraph {
            slot: GraphSlot::OfWriter(writer),
        }
    }

    /// The graph behind the handle.
    fn graph_mut(&mut self) -> FfiResult<&mut SceneGraph> {
        match &mut self.slot {
            GraphSlot::Owned(g) => Ok(g),
            // SAFETY: a writer's graph handle is unregistered and freed by
            // `ygg_writer_destroy` before the writer's box is freed, so while this handle
            // resolves, `w` points to the scene writer inside the live (boxed, unmoved)
            // writer handle that made it; the C API forbids
            // using a writer and its graph from two threads at once, so this is the only
            // reference into the writer during the call.
            GraphSlot::OfWriter(w) => Ok(unsafe { w.as_mut() }.graph_mut()),
        }
    }

    /// Takes the owned graph out (leaving an empty one), for a writer to adopt.
    pub(crate) fn take_owned(&mut self) -> FfiResult<SceneGraph> {
        match &mut self.slot {
            GraphSlot::Owned(g) => Ok(std::mem::take(g)),
            GraphSlot::OfWriter(_) => {
                Err(FfiError::invalid("the graph already belongs to a writer"))
            }
        }
    }

    /// Layers of the graph the handle owns (`None` for a writer's graph).
    pub(crate) fn owned_layer_count(&self) -> Option<usize> {
        match &self.slot {
            GraphSlot::Owned(g) => Some(ygg_store::SceneView::layers(g).count()),
            GraphSlot::OfWriter(_) => None,
        }
    }

    /// Whether the handle owns its graph (rather than borrowing a writer's).
    pub(crate) fn is_owned(&self) -> bool {
        matches!(self.slot, GraphSlot::Owned(_))
    }
}

/// The graph behind a handle argument.
pub(crate) fn graph_arg<'a>(graph: *mut YggGraph) -> FfiResult<&'a mut SceneGraph> {
    handle::resolve_mut(graph, "graph")?.graph_mut()
}

/// Runs a mutation; its refusal becomes `YGG_STATUS_GRAPH_EDIT` (graph unchanged).
fn edit<T>(graph: *mut YggGraph, f: impl FnOnce(&mut SceneGraph) -> EditResult<T>) -> FfiResult<T> {
    f(graph_arg(graph)?).map_err(|e| FfiError::new(YggStatus::GraphEdit, e.to_string()))
}

/// Creates an empty graph.
///
/// Ownership: `*out` receives a new handle that the caller destroys with
/// `ygg_graph_destroy` (or hands to `ygg_writer_create`).
///
/// # Safety
/// `out` is null (an error) or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_graph_create(out: *mut *mut YggGraph) -> YggStatus {
    guard("ygg_graph_create", || {
        // SAFETY: the caller's contract for `out`.
        let out = unsafe { Out::new(out, "out") }?;
        out.write(handle::register(YggGraph {
            slot: GraphSlot::Owned(SceneGraph::new()),
        }));
        Ok(())
    })
}

/// Destroys a graph the caller owns. A writer's graph (`ygg_writer_graph`) is refused:
/// it goes with its writer.
///
/// # Safety
/// `graph` is not used by another thread during the call.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_graph_destroy(graph: *mut YggGraph) -> YggStatus {
    guard("ygg_graph_destroy", || {
        if !handle::resolve(graph, "graph")?.is_owned() {
            return Err(FfiError::invalid(
                "the graph belongs to a writer; destroy the writer instead",
            ));
        }
        drop(handle::unregister(graph, "graph")?);
        Ok(())
    })
}

/// Adds an empty layer named `name`; `*layer` receives its id.
///
/// # Safety
/// `name` is null or NUL-terminated; `layer` is null or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_graph_add_layer(
    graph: *mut YggGraph,
    name: *const c_char,
    layer: *mut u32,
) -> YggStatus {
    guard("ygg_graph_add_layer", || {
        // SAFETY: the caller's contract for `name` and `layer`.
        let (name, out) = unsafe { (str_arg(name, "name")?, Out::new(layer, "layer")?) };
        out.write(edit(graph, |g| g.add_layer(name))?.0);
        Ok(())
    })
}

/// The id of the layer named `name` (`YGG_STATUS_GRAPH_EDIT` if none).
///
/// # Safety
/// `name` is null or NUL-terminated; `layer` is null or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_graph_layer_id(
    graph: *mut YggGraph,
    name: *const c_char,
    layer: *mut u32,
) -> YggStatus {
    guard("ygg_graph_layer_id", || {
        // SAFETY: the caller's contract for `name` and `layer`.
        let (name, out) = unsafe { (str_arg(name, "name")?, Out::new(layer, "layer")?) };
        out.write(edit(graph, |g| g.layer_id(name))?.0);
        Ok(())
    })
}

/// Removes a layer with all its nodes (their edges and nestings go with them) and its
/// DAG edges.
///
/// # Safety
/// `graph` is not used by another thread during the call.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_graph_remove_layer(graph: *mut YggGraph, layer: u32) -> YggStatus {
    guard("ygg_graph_remove_layer", || {
        edit(graph, |g| g.remove_layer(LayerId(layer)))
    })
}

/// Adds the DAG edge `parent -> child` (`parent` encompasses `child`); refused if it
/// would close a cycle.
///
/// # Safety
/// `graph` is not used by another thread during the call.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_graph_add_layer_edge(
    graph: *mut YggGraph,
    parent: u32,
    child: u32,
) -> YggStatus {
    guard("ygg_graph_add_layer_edge", || {
        edit(graph, |g| g.add_layer_edge(LayerId(parent), LayerId(child)))
    })
}

/// Removes the DAG edge `parent -> child` (refused while nestings use it).
///
/// # Safety
/// `graph` is not used by another thread during the call.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_graph_remove_layer_edge(
    graph: *mut YggGraph,
    parent: u32,
    child: u32,
) -> YggStatus {
    guard("ygg_graph_remove_layer_edge", || {
        edit(graph, |g| {
            g.remove_layer_edge(LayerId(parent), LayerId(child))
        })
    })
}

/// Adds node `node` to `layer`.
///
/// # Safety
/// `graph` is not used by another thread during the call.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_graph_add_node(
    graph: *mut YggGraph,
    node: u64,
    layer: u32,
) -> YggStatus {
    guard("ygg_graph_add_node", || {
        edit(graph, |g| g.add_node(NodeId(node), LayerId(layer)))
    })
}

/// Removes a node, its edges (both directions) and its nesting; its children stay,
/// un-nested.
///
/// # Safety
/// `graph` is not used by another thread during the call.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_graph_remove_node(graph: *mut YggGraph, node: u64) -> YggStatus {
    guard("ygg_graph_remove_node", || {
        edit(graph, |g| g.remove_node(NodeId(node)))
    })
}

/// Sets a node's geometry to `count` points, `xyz` holding `3 * count` floats (x y z of
/// each; copied). `count == 0` clears it (`xyz` may then be null). Boxes and indexes
/// above the node are updated.
///
/// # Safety
/// `xyz` is null or holds `3 * count` readable floats.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_graph_set_geometry(
    graph: *mut YggGraph,
    node: u64,
    xyz: *const f32,
    count: usize,
) -> YggStatus {
    guard("ygg_graph_set_geometry", || {
        // SAFETY: the caller's contract for `xyz` and `count`.
        let points = unsafe { points_arg(xyz, count, "xyz") }?;
        edit(graph, |g| g.set_geometry(NodeId(node), points.to_vec()))
    })
}

/// Appends `count` points to a node's geometry, `xyz` holding `3 * count` floats (x y z
/// of each; copied): a growing mesh costs the appended points, not its whole list.
/// `count == 0` changes nothing (`xyz` may then be null). Boxes and indexes above the
/// node are updated; a non-finite coordinate is refused and nothing changes.
///
/// # Safety
/// `xyz` is null or holds `3 * count` readable floats.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_graph_append_points(
    graph: *mut YggGraph,
    node: u64,
    xyz: *const f32,
    count: usize,
) -> YggStatus {
    guard("ygg_graph_append_points", || {
        // SAFETY: the caller's contract for `xyz` and `count`.
        let points = unsafe { points_arg(xyz, count, "xyz") }?;
        edit(graph, |g| g.append_points(NodeId(node), points))
    })
}

/// Sets feature `key` of a node (any previous value of the key is replaced).
fn set_feature(graph: *mut YggGraph, node: u64, key: &str, value: FeatureValue) -> FfiResult {
    edit(graph, |g| g.set_feature(NodeId(node), key, value))
}

/// Sets a string feature (both strings copied).
///
/// # Safety
/// `key` and `value` are null or NUL-terminated.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_graph_set_feature_str(
    graph: *mut YggGraph,
    node: u64,
    key: *const c_char,
    value: *const c_char,
) -> YggStatus {
    guard("ygg_graph_set_feature_str", || {
        // SAFETY: the caller's contract for `key` and `value`.
        let (key, value) = unsafe { (str_arg(key, "key")?, str_arg(value, "value")?) };
        set_feature(graph, node, key, FeatureValue::from(value))
    })
}

/// Sets an integer feature.
///
/// # Safety
/// `key` is null or NUL-terminated.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_graph_set_feature_int(
    graph: *mut YggGraph,
    node: u64,
    key: *const c_char,
    value: i64,
) -> YggStatus {
    guard("ygg_graph_set_feature_int", || {
        // SAFETY: the caller's contract for `key`.
        let key = unsafe { str_arg(key, "key") }?;
        set_feature(graph, node, key, FeatureValue::Int(value))
    })
}

/// Sets a float feature (NaN is refused).
///
/// # Safety
/// `key` is null or NUL-terminated.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_graph_set_feature_float(
    graph: *mut YggGraph,
    node: u64,
    key: *const c_char,
    value: f64,
) -> YggStatus {
    guard("ygg_graph_set_feature_float", || {
        // SAFETY: the caller's contract for `key`.
        let key = unsafe { str_arg(key, "key") }?;
        set_feature(graph, node, key, FeatureValue::Float(value))
    })
}

/// Sets a boolean feature.
///
/// # Safety
/// `key` is null or NUL-terminated.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_graph_set_feature_bool(
    graph: *mut YggGraph,
    node: u64,
    key: *const c_char,
    value: bool,
) -> YggStatus {
    guard("ygg_graph_set_feature_bool", || {
        // SAFETY: the caller's contract for `key`.
        let key = unsafe { str_arg(key, "key") }?;
        set_feature(graph, node, key, FeatureValue::Bool(value))
    })
}

/// Removes feature `key` from a node.
///
/// # Safety
/// `key` is null or NUL-terminated.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_graph_remove_feature(
    graph: *mut YggGraph,
    node: u64,
    key: *const c_char,
) -> YggStatus {
    guard("ygg_graph_remove_feature", || {
        // SAFETY: the caller's contract for `key`.
        let key = unsafe { str_arg(key, "key") }?;
        edit(graph, |g| g.remove_feature(NodeId(node), key))
    })
}

/// Adds a label to a node's label set.
///
/// # Safety
/// `label` is null or NUL-terminated.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_graph_add_label(
    graph: *mut YggGraph,
    node: u64,
    label: *const c_char,
) -> YggStatus {
    guard("ygg_graph_add_label", || {
        // SAFETY: the caller's contract for `label`.
        let label = unsafe { str_arg(label, "label") }?;
        edit(graph, |g| g.add_label(NodeId(node), label))
    })
}

/// Removes a label from a node.
///
/// # Safety
/// `label` is null or NUL-terminated.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_graph_remove_label(
    graph: *mut YggGraph,
    node: u64,
    label: *const c_char,
) -> YggStatus {
    guard("ygg_graph_remove_label", || {
        // SAFETY: the caller's contract for `label`.
        let label = unsafe { str_arg(label, "label") }?;
        edit(graph, |g| g.remove_label(NodeId(node), label))
    })
}

/// Adds the edge `source -> target` (same layer) with a description.
///
/// # Safety
/// `description` is null or NUL-terminated.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_graph_add_edge(
    graph: *mut YggGraph,
    source: u64,
    target: u64,
    description: *const c_char,
) -> YggStatus {
    guard("ygg_graph_add_edge", || {
        // SAFETY: the caller's contract for `description`.
        let description = unsafe { str_arg(description, "description") }?;
        edit(graph, |g| {
            g.add_edge(NodeId(source), NodeId(target), description)
        })
    })
}

/// Removes the edge `source -> target`.
///
/// # Safety
/// `graph` is not used by another thread during the call.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_graph_remove_edge(
    graph: *mut YggGraph,
    source: u64,
    target: u64,
) -> YggStatus {
    guard("ygg_graph_remove_edge", || {
        edit(graph, |g| g.remove_edge(NodeId(source), NodeId(target)))
    })
}

/// Nests `child` under `parent` (needs the DAG edge from `parent`'s layer to `child`'s;
/// a node has at most one parent).
///
/// # Safety
/// `graph` is not used by another thread during the call.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_graph_nest(
    graph: *mut YggGraph,
    parent: u64,
    child: u64,
) -> YggStatus {
    guard("ygg_graph_nest", || {
        edit(graph, |g| g.nest(NodeId(parent), NodeId(child)))
    })
}

/// Removes `child`'s nesting under its parent.
///
/// # Safety
/// `graph` is not used by another thread during the call.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_graph_unnest(graph: *mut YggGraph, child: u64) -> YggStatus {
    guard("ygg_graph_unnest", || {
        edit(graph, |g| g.unnest(NodeId(child)))
    })
}

/// Keeps the exact bounding box of a node's sub-tree from now on.
///
/// # Safety
/// `graph` is not used by another thread during the call.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_graph_enable_bounding_box(
    graph: *mut YggGraph,
    node: u64,
) -> YggStatus {
    guard("ygg_graph_enable_bounding_box", || {
        edit(graph, |g| g.enable_bounding_box(NodeId(node)))
    })
}

/// Stops keeping a node's bounding box.
///
/// # Safety
/// `graph` is not used by another thread during the call.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_graph_disable_bounding_box(
    graph: *mut YggGraph,
    node: u64,
) -> YggStatus {
    guard("ygg_graph_disable_bounding_box", || {
        edit(graph, |g| g.disable_bounding_box(NodeId(node)))
    })
}

/// Keeps a live kd-tree over every point of `layer` (layer-scope spatial queries).
///
/// # Safety
/// `graph` is not used by another thread during the call.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_graph_enable_layer_index(
    graph: *mut YggGraph,
    layer: u32,
) -> YggStatus {
    guard("ygg_graph_enable_layer_index", || {
        edit(graph, |g| g.enable_layer_index(LayerId(layer)))
    })
}

/// Drops a layer's index.
///
/// # Safety
/// `graph` is not used by another thread during the call.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_graph_disable_layer_index(
    graph: *mut YggGraph,
    layer: u32,
) -> YggStatus {
    guard("ygg_graph_disable_layer_index", || {
        edit(graph, |g| g.disable_layer_index(LayerId(layer)))
    })
}

/// Keeps a live kd-tree over every point in a node's sub-tree (`nearest_in_subtree`,
/// `visible`).
///
/// # Safety
/// `graph` is not used by another thread during the call.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_graph_enable_node_index(graph: *mut YggGraph, node: u64) -> YggStatus {
    guard("ygg_graph_enable_node_index", || {
        edit(graph, |g| g.enable_node_index(NodeId(node)))
    })
}

/// Drops a node's index.
///
/// # Safety
/// `graph` is not used by another thread during the call.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_graph_disable_node_index(
    graph: *mut YggGraph,
    node: u64,
) -> YggStatus {
    guard("ygg_graph_disable_node_index", || {
        edit(graph, |g| g.disable_node_index(NodeId(node)))
    })
}

/// The number of nodes.
///
/// # Safety
/// `count` is null or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_graph_node_count(
    graph: *mut YggGraph,
    count: *mut usize,
) -> YggStatus {
    guard("ygg_graph_node_count", || {
        // SAFETY: the caller's contract for `count`.
        let out = unsafe { Out::new(count, "count") }?;
        out.write(graph_arg(graph)?.node_count());
        Ok(())
    })
}

/// Writes the graph to a `.ygg` snapshot file at `path` (written aside and renamed: a
/// failure leaves any previous file intact).
///
/// # Safety
/// `path` is null or NUL-terminated.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_graph_save(graph: *mut YggGraph, path: *const c_char) -> YggStatus {
    guard("ygg_graph_save", || {
        // SAFETY: the caller's contract for `path`.
        let path = unsafe { str_arg(path, "path") }?;
        graph_arg(graph)?
            .save(path)
            .map_err(FfiError::wrap(YggStatus::Io, "save"))
    })
}

/// Imports a Spark-DSG file (JSON, `.json.gz` or binary `.sparkdsg`) and lays it out in
/// one of the paper's layouts: `layout` is `"vanilla"`, `"chocolate"`, `"mint"` or
/// `"saffron"`. Strict unless `lenient` (which drops what cannot be imported, as
/// `ygg import --lenient` does).
///
/// Ownership: `*out` receives a new graph handle the caller destroys.
///
/// # Safety
/// `path` and `layout` are null or NUL-terminated; `out` is null or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_graph_import_dsg(
    path: *const c_char,
    layout: *const c_char,
    lenient: bool,
    out: *mut *mut YggGraph,
) -> YggStatus {
    guard("ygg_graph_import_dsg", || {
        // SAFETY: the caller's contract for `path`, `layout` and `out`.
        let (path, layout_name, out) = unsafe {
            (
                str_arg(path, "path")?,
                str_arg(layout, "layout")?,
                Out::new(out, "out")?,
            )
        };
        let layout: Layout = layout_name.parse().map_err(FfiError::invalid)?;
        let options = if lenient {
            ImportOptions::LENIENT
        } else {
            ImportOptions::STRICT
        };
        let imported =
            read_file_with(path, options).map_err(FfiError::wrap(YggStatus::Import, "import"))?;
        let graph = layout::build(&imported.graph, layout)
            .map_err(FfiError::wrap(YggStatus::Import, "layout"))?;
        out.write(handle::register(YggGraph {
            slot: GraphSlot::Owned(graph),
        }));
        Ok(())
    })
}
