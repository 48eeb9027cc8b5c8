//! Live kd-tree against brute force.

use super::*;
use crate::distance_squared;
use rand::{Rng, SeedableRng};

fn brute_nearest(entries: &[Entry], c: &Point, k: usize) -> Vec<f32> {
    let mut d: Vec<f32> = entries.iter().map(|e| distance_squared(&e.p, c)).collect();
    d.sort_by(|a, b| a.total_cmp(b));
    d.truncate(k);
    d
}

fn brute_within(entries: &[Entry], c: &Point, r2: f32) -> Vec<(u32, u32)> {
    let mut v: Vec<(u32, u32)> = entries
        .iter()
        .filter(|e| distance_squared(&e.p, c) <= r2)
        .map(|e| (e.item, distance_squared(&e.p, c).to_bits()))
        .collect();
    v.sort_unstable();
    v
}

fn check_queries(t: &LiveKdTree, model: &[Entry], rng: &mut impl Rng) {
    t.check().unwrap();
    assert_eq!(t.len(), model.len());
    for _ in 0..20 {
        let c = [
            rng.gen_range(-2.0..12.0),
            rng.gen_range(-2.0..12.0),
            rng.gen_range(-1.0..2.0),
        ];
        let k = rng.gen_range(1..12);
        // The k smallest distances, through the visitor with a k-best bound.
        let mut best: Vec<f32> = Vec::new();
        t.nearest_visit(&c, |d, item| {
            assert!(
                model
                    .iter()
                    .any(|e| e.item == item && distance_squared(&e.p, &c) == d)
            );
            let at = best.partition_point(|&x| x <= d);
            best.insert(at, d);
            best.truncate(k);
            if best.len() == k {
                best[k - 1]
            } else {
                f32::INFINITY
            }
        });
        assert_eq!(best, brute_nearest(model, &c, k));
        let r2 = rng.gen_range(0.0..9.0f32);
        let mut w = Vec::new();
        t.within(&c, r2, &mut |d, item, _| w.push((item, d.to_bits())));
        w.sort_unstable();
        assert_eq!(w, brute_within(model, &c, r2));
    }
}

#[test]
fn random_inserts_and_removes_match_brute_force() {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
    let mut t = LiveKdTree::new();
    let mut model: Vec<Entry> = Vec::new();
    for step in 0..4000 {
        if model.is_empty() || rng.gen_bool(0.65) {
            // Points on a coarse grid so that duplicates and shared coordinates occur.
            let p = [
                rng.gen_range(0..40) as f32 * 0.25,
                rng.gen_range(0..40) as f32 * 0.25,
                rng.gen_range(0..3) as f32 * 0.5,
            ];
            let e = Entry {
                p,
                item: rng.gen_range(0..50),
            };
            t.insert(e.p, e.item);
            model.push(e);
        } else {
            let i = rng.gen_range(0..model.len());
            let e = model.swap_remove(i);
            assert!(t.remove(e.p, e.item));
        }
        if step % 200 == 0 {
            check_queries(&t, &model, &mut rng);
        }
    }
    check_queries(&t, &model, &mut rng);
    assert!(!t.remove([99.0, 0.0, 0.0], 1));
}

#[test]
fn many_identical_points_chain_and_unchain() {
    let mut t = LiveKdTree::new();
    for i in 0..200 {
        t.insert([1.0, 2.0, 3.0], i);
    }
    t.insert([1.0, 2.0, 4.0], 999);
    t.check().unwrap();
    assert_eq!(t.len(), 201);
    let mut seen = Vec::new();
    t.nearest_visit(&[1.0, 2.0, 3.0], |d, item| {
        seen.push((d, item));
        f32::INFINITY
    });
    seen.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    assert_eq!(seen.len(), 201);
    assert_eq!(seen[200], (1.0, 999));
    for i in 0..200 {
        assert!(t.remove([1.0, 2.0, 3.0], i));
        t.check().unwrap();
    }
    assert_eq!(
        t.entries(),
        vec![Entry {
            p: [1.0, 2.0, 4.0],
            item: 999
        }]
    );
}

#[test]
fn a_wall_of_points_sharing_one_coordinate_is_indexed() {
    // kiddo's MutableKdTree fails here (a full bucket cannot split on x).
    let mut t = LiveKdTree::new();
    for i in 0..5000u32 {
        t.insert([1.0, (i % 71) as f32, (i / 71) as f32], i);
    }
    t.check().unwrap();
    assert_eq!(t.len(), 5000);
}

#[test]
fn sequential_inserts_stay_balanced() {
    let mut t = LiveKdTree::new();
    for i in 0..100_000u32 {
        t.insert([i as f32, 0.0, 0.0], i);
    }
    t.check().unwrap();
    assert!(t.depth() <= depth_limit(t.len()) + 1, "depth {}", t.depth());
    for i in 0..99_000u32 {
        assert!(t.remove([i as f32, 0.0, 0.0], i));
    }
    t.check().unwrap();
    assert!(t.depth() <= depth_limit(t.len()), "depth {}", t.depth());
}

#[test]
fn located_updates_match_plain_ones() {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
    let empty = LiveKdTree::new();
    let point = |rng: &mut rand_chacha::ChaCha8Rng| {
        [
            rng.gen_range(0..60) as f32 * 0.25,
            rng.gen_range(0..60) as f32 * 0.25,
            rng.gen_range(0..2) as f32,
        ]
    };
    let entries: Vec<Entry> = (0..3000)
        .map(|i| Entry {
            p: point(&mut rng),
            item: i,
        })
        .collect();
    let mut t = LiveKdTree::from_entries(entries.clone());
    let mut plain = t.clone();
    let mut model = entries;
    for step in 0..6000 {
        // Move (remove one entry, add up to three) through located updates; the same
        // through plain ones.
        let e = model.swap_remove(rng.gen_range(0..model.len()));
        let added: Vec<Entry> = (0..rng.gen_range(0..4))
            .map(|_| Entry {
                p: if rng.gen_bool(0.1) {
                    e.p
                } else {
                    point(&mut rng)
                },
                item: e.item,
            })
            .collect();
        let ps: Vec<Point> = added.iter().map(|a| a.p).collect();
        let mut at = [Located::default(); 8];
        LiveKdTree::locate(&[&t, &empty], &[&[e.p], &ps], &mut at[..2 * (1 + ps.len())]);
        let shape = t.shape();
        assert!(t.remove_located(e.p, e.item, at[0], shape));
        assert!(plain.remove(e.p, e.item));
        for (a, l) in added.iter().zip(&at[1..]) {
            t.insert_located(a.p, a.item, *l, shape);
            plain.insert(a.p, a.item);
        }
        model.extend(added);
        if step % 500 == 0 {
            t.check().unwrap();
            let sorted = |t: &LiveKdTree| {
                let mut v: Vec<_> = t
                    .entries()
                    .iter()
                    .map(|e| (e.item, e.p.map(f32::to_bits)))
                    .collect();
                v.sort_unstable();
                v
            };
            assert_eq!(sorted(&t), sorted(&plain));
            assert_eq!(t.len(), model.len());
        }
    }
    // A located leaf is the one a descent reaches, at the path's depth.
    let probe: Vec<Point> = (0..50).map(|_| point(&mut rng)).collect();
    let mut at = vec![Located::default(); 50];
    LiveKdTree::locate(&[&t], &[&probe], &mut at);
    for (p, a) in probe.iter().zip(&at) {
        let (mut r, mut depth) = (t.root, 0);
        while !is_leaf(r) {
            let n = &t.inners[r as usize];
            r = if p[n.dim as usize] < n.split {
                n.left
            } else {
                n.right
            };
            depth += 1;
        }
        assert_eq!((a.leaf, a.depth), (r, depth));
    }
    // A stale location (the shape changed since) takes the ordinary path.
    let old_shape = t.shape();
    for i in 0..200 {
        t.insert(point(&mut rng), 10_000 + i);
    }
    assert_ne!(t.shape(), old_shape);
    t.insert_located([1.0, 1.0, 0.0], 99_999, at[0], old_shape);
    assert!(t.remove_located([1.0, 1.0, 0.0], 99_999, at[1], old_shape));
    t.check().unwrap();
}

#[test]
fn bulk_build_matches_brute_force() {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
    let model: Vec<Entry> = (0..3000)
        .map(|i| Entry {
            p: [
                rng.gen_range(0.0..10.0),
                rng.gen_range(0.0..10.0),
                rng.gen_range(0.0..1.0),
            ],
            item: i,
        })
        .collect();
    let t = LiveKdTree::from_entries(model.clone());
    check_queries(&t, &model, &mut rng);
    // Leaves 7/8 full after a bulk build: 18.6 bytes per point plus inner nodes.
    assert!(t.memory_bytes() < 20 * model.len(), "{}", t.memory_bytes());
}
