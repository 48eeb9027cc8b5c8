//! Zero-copy numpy views of a node's points (a copy for the rare node whose points cross
//! a chunk boundary of a chunked layer).

#![allow(
    unsafe_code,
    reason = "a numpy array borrowing the snapshot's bytes, owned by the Scene object"
)]

use numpy::ndarray::ArrayView2;
use numpy::{PyArray2, PyArrayMethods};
use pyo3::PyClass;
use pyo3::prelude::*;
use pyo3::pyclass::boolean_struct::True;
use ygg_store::{NodeId, SceneView};

use crate::errors::unknown_node;
use crate::snapshot::SnapshotView;

/// A frozen Python object that holds one snapshot for its whole life (a `Node`): the
/// numpy base of the arrays viewing that snapshot's points.
pub trait SnapshotOwner: PyClass<Frozen = True> + Sync {
    /// The snapshot it holds; always the same one.
    fn snapshot(&self) -> &SnapshotView;
}

/// A read-only `(n, 3)` `float32` array over node `id`'s points in `owner`'s snapshot,
/// whose numpy base is `owner`: the snapshot stays mapped while the array lives. A node
/// whose points lie in several chunks of a chunked layer (a mesh node of more than 32,768
/// points by default) gets a read-only copy instead.
pub fn points_array<'py, O: SnapshotOwner>(
    owner: &Bound<'py, O>,
    id: NodeId,
) -> PyResult<Bound<'py, PyArray2<f32>>> {
    let view = owner.get().snapshot().view();
    let node = view.node(id).ok_or_else(|| unknown_node(id.0))?;
    let points = view.points(node);
    let Some(points) = points.as_slice() else {
        let copy = PyArray2::from_vec2(
            owner.py(),
            &points.iter().map(|p| p.to_vec()).collect::<Vec<_>>(),
        )?;
        copy.readwrite().make_nonwriteable();
        return Ok(copy);
    };
    let flat: &[f32] = points.as_flattened();
    let array = ArrayView2::from_shape((points.len(), 3), flat)
        .expect("a slice of [f32; 3] has exactly 3 columns");
    // SAFETY: `borrow_from_array` requires that the memory behind `array` stays valid and
    // is never reallocated until `container` (the numpy base) is dropped. The slice lies in
    // the bytes of the snapshot that `owner` holds for its whole life (`SnapshotOwner`;
    // frozen, so never replaced): a mapped `.ygg` file, an aligned in-memory archive, or
    // shared-memory samples held by a `SceneSnapshot`; none of these backings is written
    // or moved while held. The container is `owner`, so the array keeps the snapshot
    // alive.
    let out = unsafe { PyArray2::borrow_from_array(&array, owner.clone().into_any()) };
    // The snapshot is read-only (shared memory is mapped read-only in readers).
    out.readwrite().make_nonwriteable();
    Ok(out)
}
