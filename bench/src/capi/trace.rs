//! The recorded SLAM-style stream as a file the C++ side reads
//! (`bench/cpp/stream_replay.cpp` parses the same format).
//!
//! Little-endian throughout: `u32` tick count; per tick a `u32` edit count, then each
//! edit as a `u8` op and its fields:
//!
//! | op | edit | fields |
//! |---|---|---|
//! | 0 | add_node | `u64` node, `u32` layer |
//! | 1 | set_geometry | `u64` node, `u32` n, `3n` x `f32` |
//! | 2 | set_feature | `u64` node, str key, `u8` kind (0 str, 1 int, 2 float, 3 bool), value (str, `i64`, `f64`, `u8`) |
//! | 3 | add_label | `u64` node, str label |
//! | 4 | add_edge | `u64` source, `u64` target, str description |
//! | 5 | nest | `u64` parent, `u64` child |
//! | 6 | append_points | `u64` node, `u32` n, `3n` x `f32` |
//!
//! A str is a `u32` byte length and the UTF-8 bytes.

use ygg_dsg::replay::Edit;
use ygg_store::{FeatureValue, NodeId, Point};

fn str_field(out: &mut Vec<u8>, s: &str) {
    out.extend_from_slice(&(s.len() as u32).to_le_bytes());
    out.extend_from_slice(s.as_bytes());
}

/// An edit of a node's points: `op`, the node, the point count and the coordinates.
fn points_edit(out: &mut Vec<u8>, op: u8, node: NodeId, points: &[Point]) {
    out.push(op);
    out.extend_from_slice(&node.0.to_le_bytes());
    out.extend_from_slice(&(points.len() as u32).to_le_bytes());
    for v in points.iter().flatten() {
        out.extend_from_slice(&v.to_le_bytes());
    }
}

/// The trace file's bytes for `ticks` (each tick's edits in order).
pub fn encode(ticks: &[Vec<Edit>]) -> Vec<u8> {
    let mut out = Vec::new();
    out.extend_from_slice(&(ticks.len() as u32).to_le_bytes());
    for edits in ticks {
        out.extend_from_slice(&(edits.len() as u32).to_le_bytes());
        for edit in edits {
            match edit {
                Edit::AddNode { node, layer } => {
                    out.push(0);
                    out.extend_from_slice(&node.0.to_le_bytes());
                    out.extend_from_slice(&layer.0.to_le_bytes());
                }
                Edit::SetGeometry { node, points } => points_edit(&mut out, 1, *node, points),
                Edit::AppendPoints { node, points } => points_edit(&mut out, 6, *node, points),
                Edit::SetFeature { node, key, value } => {
                    out.push(2);
                    out.extend_from_slice(&node.0.to_le_bytes());
                    str_field(&mut out, key);
                    match value {
                        FeatureValue::Str(s) => {
                            out.push(0);
                            str_field(&mut out, s);
                        }
                        FeatureValue::Int(v) => {
                            out.push(1);
                            out.extend_from_slice(&v.to_le_bytes());
                        }
                        FeatureValue::Float(v) => {
                            out.push(2);
                            out.extend_from_slice(&v.to_le_bytes());
                        }
                        FeatureValue::Bool(v) => {
                            out.push(3);
                            out.push(u8::from(*v));
                        }
                    }
                }
                Edit::AddLabel { node, label } => {
                    out.push(3);
                    out.extend_from_slice(&node.0.to_le_bytes());
                    str_field(&mut out, label);
                }
                Edit::AddEdge {
                    source,
                    target,
                    description,
                } => {
                    out.push(4);
                    out.extend_from_slice(&source.0.to_le_bytes());
                    out.extend_from_slice(&target.0.to_le_bytes());
                    str_field(&mut out, description);
                }
                Edit::Nest { parent, child } => {
                    out.push(5);
                    out.extend_from_slice(&parent.0.to_le_bytes());
                    out.extend_from_slice(&child.0.to_le_bytes());
                }
            }
        }
    }
    out
}
