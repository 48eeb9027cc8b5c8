//! Where the agent is, on a snapshot handle (`ygg_snapshot_newest_pose`,
//! `ygg_snapshot_room_of`, `ygg_snapshot_room_scope`, `ygg_snapshot_owners`): the calls
//! of `ygg_dsg::layout`, for scenes in Spark-DSG's layer names (`AGENTS`, `ROOMS`, ...).
//!
//! Thread-safety: as the snapshot (any number of threads at once).

use crate::args::{Out, ids_arg, point_arg};
use crate::errors::{YggStatus, guard};
use crate::lists::{YggNodeList, deliver_ids};
use crate::snapshot::{YggSnapshot, view_arg};
use ygg_dsg::layout;
use ygg_store::NodeId;

/// The newest agent pose of a scene (`ygg_snapshot_newest_pose`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct YggAgentPose {
    /// The pose node: the largest id of the `AGENTS` layer with a point.
    pub node: u64,
    /// Its position (x y z).
    pub position: [f32; 3],
    /// The previous pose's position (1 m behind along -x when there is a single pose).
    pub previous: [f32; 3],
    /// The unit direction of travel, from `previous` to `position` (+x when they
    /// coincide).
    pub heading: [f32; 3],
}

/// Where a room's objects live in a per-room layout (`ygg_snapshot_room_scope`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct YggRoomScope {
    /// The room's claimed-mesh layer: its objects' mesh nodes.
    pub mesh_layer: u32,
    /// The room's claimed group node: every object of the room nests under it.
    pub claimed: u64,
}

/// The newest agent pose (the `AGENTS` layer's largest id with a point) and the pose
/// before it: `*found` says whether there is one (no `AGENTS` layer, or no pose with a
/// point yet, is `false`); `*pose` is written only when found.
///
/// # Safety
/// `found` and `pose` are null or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_snapshot_newest_pose(
    snapshot: *const YggSnapshot,
    found: *mut bool,
    pose: *mut YggAgentPose,
) -> YggStatus {
    guard("ygg_snapshot_newest_pose", || {
        // SAFETY: the caller's contract for `found` and `pose`.
        let (found, out) = unsafe { (Out::new(found, "found")?, Out::new(pose, "pose")?) };
        let newest = layout::newest_pose(view_arg(snapshot)?);
        found.write(newest.is_some());
        if let Some(p) = newest {
            out.write(YggAgentPose {
                node: p.node.0,
                position: p.position,
                previous: p.previous,
                heading: p.heading(),
            });
        }
        Ok(())
    })
}

/// The room (a node of the `ROOMS` layer) whose box holds `point` in x and y, the
/// smallest id when several do: `*found` says whether one does, `*room` is its id (0 when
/// none).
///
/// # Safety
/// `point` is null or holds 3 floats; `found` and `room` are null or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_snapshot_room_of(
    snapshot: *const YggSnapshot,
    point: *const f32,
    found: *mut bool,
    room: *mut u64,
) -> YggStatus {
    guard("ygg_snapshot_room_of", || {
        // SAFETY: the caller's contract for `point`, `found` and `room`.
        let (p, found, out) = unsafe {
            (
                point_arg(point, "point")?,
                Out::new(found, "found")?,
                Out::new(room, "room")?,
            )
        };
        let holder = layout::room_of(view_arg(snapshot)?, &p);
        found.write(holder.is_some());
        out.write(holder.map_or(0, |r| r.0));
        Ok(())
    })
}

/// Where `room`'s objects live in a per-room layout (chocolate, mint, saffron): its
/// claimed-mesh layer and claimed group node (`ygg_snapshot_*` object queries are
/// answered over a room by restricting to the group's sub-tree). `*found` is `false` in
/// another layout or for an unknown room; `*scope` is written only when found.
///
/// # Safety
/// `found` and `scope` are null or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_snapshot_room_scope(
    snapshot: *const YggSnapshot,
    room: u64,
    found: *mut bool,
    scope: *mut YggRoomScope,
) -> YggStatus {
    guard("ygg_snapshot_room_scope", || {
        // SAFETY: the caller's contract for `found` and `scope`.
        let (found, out) = unsafe { (Out::new(found, "found")?, Out::new(scope, "scope")?) };
        let where_ = layout::room_scope(view_arg(snapshot)?, NodeId(room));
        found.write(where_.is_some());
        if let Some(s) = where_ {
            out.write(YggRoomScope {
                mesh_layer: s.mesh_layer.0,
                claimed: s.claimed.0,
            });
        }
        Ok(())
    })
}

/// The distinct parents of the `count` nodes in `nodes` (the objects owning mesh nodes),
/// ascending; nodes without a parent or not in the snapshot are left out.
///
/// Ownership: `*list` is overwritten (not freed) with a list the caller frees with
/// `ygg_node_list_free`; on error it is the empty list.
///
/// # Safety
/// `nodes` is null or holds `count` ids; `list` is null or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ygg_snapshot_owners(
    snapshot: *const YggSnapshot,
    nodes: *const u64,
    count: usize,
    list: *mut YggNodeList,
) -> YggStatus {
    guard("ygg_snapshot_owners", || {
        // SAFETY: the caller's contract for `list`.
        let out = unsafe { Out::new(list, "list") }?;
        let found = (|| {
            // SAFETY: the caller's contract for `nodes` and `count`.
            let nodes = unsafe { ids_arg(nodes, count, "nodes") }?;
            let view = view_arg(snapshot)?;
            Ok(layout::owners(view, nodes.iter().map(|&n| NodeId(n))))
        })();
        deliver_ids(found, out)
    })
}
