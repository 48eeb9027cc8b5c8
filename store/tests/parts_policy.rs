//! The policy that splits a publishing writer's layers into parts (row chunks): appends
//! fill the newest part and then seal it, cold sealed parts merge like a binary counter,
//! removals drop empty parts, a bulk part is split (`store/src/snapshot/publish/parts.rs`).

use ygg_store::snapshot::SegmentCache;
use ygg_store::{LayerId, NodeId, SceneGraph};

fn poses(n: u64) -> (SceneGraph, LayerId) {
    let mut g = SceneGraph::new();
    let l = g.add_layer("poses").unwrap();
    for id in 0..n {
        g.add_node(NodeId(id), l).unwrap();
    }
    (g, l)
}

fn part_rows(cache: &mut SegmentCache, g: &mut SceneGraph, l: LayerId) -> Vec<usize> {
    cache
        .published_layer(g, l)
        .parts()
        .iter()
        .map(|p| p.segment.ids.len())
        .collect()
}

#[test]
fn appends_fill_the_tail_then_seal_it_and_cold_parts_merge_like_a_binary_counter() {
    let (mut g, l) = poses(0);
    let mut cache = SegmentCache::new().with_part_rows(4, 16);
    let mut sent_rows = 0;
    for id in 0..200u64 {
        g.add_node(NodeId(id), l).unwrap();
        let published = cache.published_layer(&mut g, l);
        let generation = g.layer_generation(l).unwrap();
        sent_rows += published
            .parts()
            .iter()
            .filter(|p| p.segment.generation == generation)
            .map(|p| p.segment.ids.len())
            .sum::<usize>();
    }
    let rows = part_rows(&mut cache, &mut g, l);
    assert_eq!(rows.iter().sum::<usize>(), 200);
    assert!(rows.iter().all(|&r| r <= 16), "{rows:?}");
    assert!(rows.len() <= 200 / 16 + 6, "{rows:?}");
    // Each append sends the tail (<= 4 rows) and merges resend each row a few times.
    assert!(sent_rows <= 200 * 4 + 200 * 3, "{sent_rows} rows sent");
    assert!(rows.iter().all(|&r| r > 0), "{rows:?}");
}

#[test]
fn removals_drop_empty_parts_and_a_bulk_part_is_split() {
    let (mut g, l) = poses(100);
    let mut cache = SegmentCache::new().with_part_rows(4, 16);
    let rows = part_rows(&mut cache, &mut g, l);
    assert_eq!(rows.len(), 7, "{rows:?}");
    for id in 0..50 {
        g.remove_node(NodeId(id)).unwrap();
    }
    let rows = part_rows(&mut cache, &mut g, l);
    assert_eq!(rows.iter().sum::<usize>(), 50);
    assert!(rows.iter().all(|&r| r > 0), "{rows:?}");
    for id in 1000..1100 {
        g.add_node(NodeId(id), l).unwrap();
    }
    let rows = part_rows(&mut cache, &mut g, l);
    assert_eq!(rows.iter().sum::<usize>(), 150);
    assert!(rows.iter().all(|&r| r <= 16), "{rows:?}");
    for id in 50..100 {
        g.remove_node(NodeId(id)).unwrap();
    }
    for id in 1000..1100 {
        g.remove_node(NodeId(id)).unwrap();
    }
    assert_eq!(part_rows(&mut cache, &mut g, l), [0]);
}
