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
    let mut sent = 0;
    for id in 0..200u64 {
        g.add_node(NodeId(id), l).unwrap();
        sent += sent_rows(&mut cache, &mut g, l);
    }
    let rows = part_rows(&mut cache, &mut g, l);
    assert_eq!(rows.iter().sum::<usize>(), 200);
    assert!(rows.iter().all(|&r| r <= 16), "{rows:?}");
    assert!(rows.len() <= 200 / 16 + 6, "{rows:?}");
    // Each append sends the tail (<= 4 rows) and merges resend each row a few times.
    assert!(sent <= 200 * 4 + 200 * 3, "{sent} rows sent");
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

/// Rows of the parts of `l` that `cache` (re)built for the graph's current state.
fn sent_rows(cache: &mut SegmentCache, g: &mut SceneGraph, l: LayerId) -> usize {
    let published = cache.published_layer(g, l);
    let generation = g.layer_generation(l).unwrap();
    published
        .parts()
        .iter()
        .filter(|p| p.segment.generation == generation)
        .map(|p| p.segment.ids.len())
        .sum()
}

#[test]
fn parts_untouched_for_long_merge_past_max_so_a_long_history_keeps_few_parts() {
    let (mut g, l) = poses(0);
    let mut cache = SegmentCache::new().with_part_rows(4, 64);
    let mut sent = 0;
    let n = 6000u64;
    for id in 0..n {
        g.add_node(NodeId(id), l).unwrap();
        sent += sent_rows(&mut cache, &mut g, l);
    }
    let rows = part_rows(&mut cache, &mut g, l);
    assert_eq!(rows.iter().sum::<usize>(), n as usize);
    // Parts untouched for 1,024 updates grow to 16 times `max` (1,024 rows): the history
    // keeps far fewer parts than n / 64 (the last 1,024 updates stay in parts of <= 64).
    assert!(rows.iter().any(|&r| r > 64), "{rows:?}");
    assert!(rows.iter().all(|&r| r <= 1024), "{rows:?}");
    assert!(
        rows.len() <= 6000 / 1024 + 1024 / 64 + 12,
        "{} parts: {rows:?}",
        rows.len()
    );
    // Each row is resent a few more times by the merges past `max`, not per append.
    assert!(
        sent <= n as usize * (4 + 10),
        "{sent} rows sent for {n} appends"
    );
    // An edit of a row in a frozen part resends it once, split into pieces of max / 2,
    // and the next edit there resends one piece.
    g.add_label(NodeId(100), "edited").unwrap();
    let first = sent_rows(&mut cache, &mut g, l);
    assert!(first > 64, "the frozen part is resent: {first}");
    g.add_label(NodeId(101), "edited").unwrap();
    let second = sent_rows(&mut cache, &mut g, l);
    assert!(second <= 32, "then one piece of max / 2: {second}");
}

#[test]
fn a_sliding_window_resends_about_a_tail_per_tick_not_its_front_part() {
    let (mut g, l) = poses(0);
    let mut cache = SegmentCache::new().with_part_rows(4, 16);
    let window = 300u64;
    let mut sent = Vec::new();
    for id in 0..6000u64 {
        g.add_node(NodeId(id), l).unwrap();
        if id >= window {
            g.remove_node(NodeId(id - window)).unwrap();
        }
        sent.push(sent_rows(&mut cache, &mut g, l));
    }
    let rows = part_rows(&mut cache, &mut g, l);
    assert_eq!(rows.iter().sum::<usize>(), window as usize);
    let late = &sent[1000..];
    let mean = late.iter().sum::<usize>() as f64 / late.len() as f64;
    // The tail (<= 4 rows), the window's front piece (<= 4 rows), and merges and splits
    // amortised: well under resending a front part of up to 16 rows every tick (11.5
    // rows a tick when a part that loses rows is not split).
    assert!(mean <= 8.0, "{mean} rows sent per tick");
}
