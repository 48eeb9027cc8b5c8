//! The writer's incremental layer segments on a realistic scene: they equal fresh ones
//! after every step of a SLAM-like stream.

use ygg_dsg::layout::{Layout, build};
use ygg_dsg::office::{OfficeParams, generate};
use ygg_store::snapshot::SegmentCache;
use ygg_store::{LayerId, NodeId, Point, SceneGraph, SceneView};
use ygg_testkit::fingerprint::segment_fingerprint;

/// The same on a realistic scene: a small office in mint layout (layer and node
/// indexes, large layers) under a SLAM-like stream — poses appended with odometry edges
/// and nested under places, object meshes moved, mesh patches grown, nodes removed.
#[test]
fn cached_layer_segments_follow_a_slam_stream_on_the_office() {
    let mut g = build(
        &generate(OfficeParams {
            seed: 3,
            scale: 0.3,
        }),
        Layout::Mint,
    )
    .unwrap();
    let layers: Vec<LayerId> = g.layers().collect();
    let nodes_of = |g: &SceneGraph, l: LayerId| -> Vec<NodeId> {
        let mut v: Vec<NodeId> = g.layer_nodes(l).map(|n| g.node_id(n)).collect();
        v.sort_unstable();
        v
    };
    let agents = g.layer_id("AGENTS").unwrap();
    let places = g.layer_id("PLACES").unwrap();
    let mut rng = 0x9E37_79B9_7F4A_7C15u64;
    let mut next = |n: usize| {
        rng ^= rng << 13;
        rng ^= rng >> 7;
        rng ^= rng << 17;
        (rng % n as u64) as usize
    };
    let mut pose = 1u64 << 60;
    let mut cache = SegmentCache::new();
    for &l in &layers {
        cache.layer_segment(&mut g, l);
    }
    let mut check = |g: &mut SceneGraph, before: &[Option<u64>], what: &str| {
        for (&l, &generation) in layers.iter().zip(before) {
            if g.layer_generation(l) != generation {
                let fresh = segment_fingerprint(&g.layer_segment(l));
                assert_eq!(
                    segment_fingerprint(cache.layer_segment(g, l)),
                    fresh,
                    "layer {l} {what}"
                );
            }
        }
    };
    let generations = |g: &SceneGraph| -> Vec<Option<u64>> {
        layers.iter().map(|&l| g.layer_generation(l)).collect()
    };
    for step in 0..40 {
        // A pose appended: new last row, an edge from the previous one, nested.
        let before = generations(&g);
        let prev = nodes_of(&g, agents).last().copied();
        pose += 1;
        g.add_node(NodeId(pose), agents).unwrap();
        g.set_geometry(NodeId(pose), vec![[step as f32 * 0.1, 1.0, 1.0]])
            .unwrap();
        if let Some(prev) = prev {
            g.add_edge(prev, NodeId(pose), "odometry").unwrap();
        }
        let ps = nodes_of(&g, places);
        let _ = g.nest(ps[next(ps.len())], NodeId(pose));
        check(
            &mut g,
            &before,
            &format!("after appending a pose at step {step}"),
        );

        // An older pose moved (rows keep their shape).
        let before = generations(&g);
        let poses = nodes_of(&g, agents);
        let p = poses[next(poses.len())];
        g.set_geometry(p, vec![[step as f32, 2.0, 1.0]]).unwrap();
        check(
            &mut g,
            &before,
            &format!("after moving a pose at step {step}"),
        );

        // A node of any layer moved, sometimes growing, relabelled or removed.
        let before = generations(&g);
        let l = layers[next(layers.len())];
        let ns = nodes_of(&g, l);
        if !ns.is_empty() {
            let n = ns[next(ns.len())];
            let pts: Vec<Point> = g.points(g.node(n).unwrap()).to_vec();
            let d = if step % 3 == 0 { 0.05 } else { -0.02 };
            let mut moved: Vec<Point> = pts.iter().map(|p| [p[0] + d, p[1], p[2]]).collect();
            if step % 4 == 0 {
                moved.push([1.0, 2.0, 0.5]);
            }
            g.set_geometry(n, moved).unwrap();
            if step % 7 == 0 {
                g.add_label(n, "moved").unwrap();
            }
            if step % 11 == 0 {
                g.remove_node(*ns.last().unwrap()).unwrap();
            }
        }
        check(
            &mut g,
            &before,
            &format!("after changing layer {l} at step {step}"),
        );
    }
}
