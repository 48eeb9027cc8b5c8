//! Spark-DSG JSON import against the fixtures (and the full office when available).

/// Named `dsg` so that `cargo test -p ygg-store dsg` selects these tests.
mod dsg {
    use std::path::{Path, PathBuf};
    use std::time::{Duration, Instant};

    use ygg_dsg::{
        DsgGraph, DsgVersion, ImportPhase, ImportProgress, LayerKey, NodeKind, NodeSymbol,
    };

    fn fixture(name: &str) -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("tests/fixtures")
            .join(name)
    }

    fn data_dir() -> PathBuf {
        std::env::var_os("YGG_DSG_DATA")
            .map(PathBuf::from)
            .unwrap_or_else(|| PathBuf::from("/work/shared/data"))
    }

    fn load(name: &str) -> DsgGraph {
        match ygg_dsg::read_file(fixture(name)) {
            Ok(g) => g,
            Err(e) => panic!("{e}"),
        }
    }

    fn count_layer(g: &DsgGraph, key: LayerKey) -> usize {
        g.counts().by_layer.get(&key).copied().unwrap_or(0)
    }

    /// Edge counts by (child prefix, parent prefix) and intra-layer (prefix, prefix).
    fn edge_kinds(g: &DsgGraph) -> std::collections::BTreeMap<String, usize> {
        let mut m = std::collections::BTreeMap::new();
        let p = |id: u64| NodeSymbol::from_id(id).prefix() as char;
        for n in &g.nodes {
            if let Some(parent) = n.parent {
                *m.entry(format!("{}>{}", p(n.id), p(parent))).or_default() += 1;
            }
        }
        for e in &g.edges {
            *m.entry(format!("{}-{}", p(e.source), p(e.target)))
                .or_default() += 1;
        }
        m
    }

    #[test]
    fn apartment_legacy_file_imports_with_documented_counts() {
        let g = load("apartment_dsg.json");
        assert_eq!(g.version, DsgVersion::LEGACY);
        let c = g.counts();
        assert_eq!(c.nodes, 296);
        assert_eq!(c.kind(NodeKind::Building), 1);
        assert_eq!(c.kind(NodeKind::Room), 1);
        assert_eq!(c.kind(NodeKind::Place), 185);
        assert_eq!(c.kind(NodeKind::Agent), 102);
        assert_eq!(c.kind(NodeKind::Object), 7);
        assert_eq!(count_layer(&g, LayerKey::AGENTS), 102);
        assert_eq!(count_layer(&g, LayerKey::OBJECTS), 7);
        assert_eq!(c.edges, 742);
        assert_eq!(c.sibling_edges, 0);
        assert_eq!(c.extra_parent_edges, 0);
        let k = edge_kinds(&g);
        assert_eq!(k["p-p"], 396);
        assert_eq!(k["p>R"], 135);
        assert_eq!(k["a>p"], 102);
        assert_eq!(k["a-a"], 101);
        assert_eq!(k["O>p"], 7);
        assert_eq!(k["R>B"], 1);
        assert_eq!(g.mesh, None);

        // Ids above 2^53 are exact.
        let a0 = NodeSymbol::new(b'a', 0).id();
        assert_eq!(a0, 6_989_586_621_679_009_792);
        let agent = g.nodes.iter().find(|n| n.id == a0).expect("a(0) present");
        assert_eq!(agent.kind, NodeKind::Agent);
        assert_eq!(agent.layer, LayerKey::AGENTS);
        assert_eq!(agent.timestamp_ns, Some(3_647_910_000));

        // Hydra names objects "O(0)": that is not a label; three semantic ids, no names.
        let objects: Vec<_> = g.nodes_of_kind(NodeKind::Object).collect();
        assert!(
            objects
                .iter()
                .all(|o| o.label.is_none() && o.name.is_some())
        );
        let mut ids: Vec<_> = objects.iter().filter_map(|o| o.semantic_label).collect();
        ids.sort_unstable();
        ids.dedup();
        assert_eq!(ids, vec![5, 11, 16]);
        assert!(
            objects
                .iter()
                .all(|o| o.bbox.is_some() && !o.mesh_connections.is_empty())
        );
        // The room's box is INVALID.
        assert!(g.nodes_of_kind(NodeKind::Room).all(|r| r.bbox.is_none()));

        let names: Vec<_> = g.layers.iter().map(|l| l.name.as_str()).collect();
        assert_eq!(names, ["OBJECTS", "AGENTS", "PLACES", "ROOMS", "BUILDINGS"]);
    }

    #[test]
    fn office_tiny_imports_with_documented_counts() {
        let g = load("office_tiny.json");
        assert_eq!(g.version, DsgVersion::V1_1_3);
        let c = g.counts();
        assert_eq!(c.nodes, 110);
        assert_eq!(c.kind(NodeKind::Building), 1);
        assert_eq!(c.kind(NodeKind::Room), 9);
        assert_eq!(c.kind(NodeKind::Place), 23);
        assert_eq!(c.kind(NodeKind::Place2d), 29);
        assert_eq!(c.kind(NodeKind::Agent), 14);
        assert_eq!(c.kind(NodeKind::Object), 34);
        assert_eq!(count_layer(&g, LayerKey::MESH_PLACES), 29);
        assert_eq!(c.edges, 270);
        assert_eq!(c.parent_edges, 109);
        assert_eq!(c.extra_parent_edges, 0);
        assert_eq!(c.mesh_vertices, 7_098);
        assert_eq!(c.mesh_faces, 11_280);

        let s = g.claim_stats().expect("mesh");
        assert_eq!(s.unclaimed, 6_270);
        assert_eq!(s.multi_claimed, 560);
        assert_eq!(s.claimed, 828);
        assert_eq!(s.total_claims, 1_388);
        assert_eq!(s.objects, 34);
        assert_eq!(s.wrong_boxes, 20);

        let h = g.object_label_histogram();
        assert_eq!(h.len(), 27);
        assert_eq!(h["light"], 4);
        assert_eq!(h["chair"], 3);
        assert_eq!(h["desk"], 2);
        assert_eq!(h["monitor"], 2);
        assert_eq!(h["bulletin"], 1);
        assert!(g.nodes_of_kind(NodeKind::Object).all(|o| o.name == o.label));

        let mesh = g.mesh.as_ref().expect("mesh");
        assert_eq!(mesh.labels.as_ref().map(Vec::len), Some(7_098));
        assert_eq!(g.labelspaces["mesh"].len(), 30);
        assert_eq!(g.labelspaces["_l2p0"][&12], "light");

        let names: Vec<_> = g.layers.iter().map(|l| l.name.as_str()).collect();
        assert_eq!(
            names,
            [
                "OBJECTS",
                "AGENTS",
                "PLACES",
                "MESH_PLACES",
                "ROOMS",
                "BUILDINGS"
            ]
        );
        assert_eq!(
            g.layer(LayerKey::OBJECTS).map(|l| l.aliases.clone()),
            Some(vec!["AGENTS".to_owned(), "OBJECTS".to_owned()])
        );

        // Room boxes equal the floor plan; the corridor is x 0-40, y 11-14, 3 m high.
        let r0 = g
            .nodes
            .iter()
            .find(|n| n.id == NodeSymbol::new(b'R', 0).id())
            .and_then(|n| n.bbox)
            .expect("R(0) box");
        assert_eq!(r0.min, [0.0, 11.0, 0.0]);
        assert_eq!(r0.max, [40.0, 14.0, 3.0]);
    }

    #[test]
    fn gzip_and_plain_files_import_identically() {
        let plain = std::fs::read(fixture("office_tiny.json")).expect("fixture");
        let mut enc = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
        std::io::Write::write_all(&mut enc, &plain).expect("gzip");
        let gz = enc.finish().expect("gzip");
        let dir = tempfile::tempdir().expect("tempdir");
        let path = dir.path().join("office_tiny.json.gz");
        std::fs::write(&path, gz).expect("write");
        let a = ygg_dsg::read_file(&path).expect("gz import");
        let b = load("office_tiny.json");
        assert_eq!(a.nodes, b.nodes);
        assert_eq!(a.edges, b.edges);
        assert_eq!(a.mesh, b.mesh);
    }

    #[test]
    fn progress_reports_every_phase_in_order() {
        let mut phases = Vec::new();
        let mut record = |p: ImportProgress| {
            if phases.last() != Some(&p.phase) {
                phases.push(p.phase);
            }
        };
        ygg_dsg::read_file_with_progress(fixture("apartment_dsg.json"), &mut record)
            .expect("import");
        assert_eq!(
            phases,
            [
                ImportPhase::Read,
                ImportPhase::Parse,
                ImportPhase::Validate,
                ImportPhase::Done
            ]
        );
    }

    #[test]
    fn missing_file_is_an_io_error_naming_it() {
        let e = ygg_dsg::read_file("/nonexistent/x.json").expect_err("no file");
        assert!(matches!(e, ygg_dsg::DsgImportError::Io { .. }));
        assert!(e.to_string().contains("/nonexistent/x.json"));
    }

    fn median(mut v: Vec<Duration>) -> Duration {
        v.sort();
        v[v.len() / 2]
    }

    /// Counts of the full office; prints read+gunzip and parse times (not asserted).
    /// The 12.9 MB file is not in the repository: run with `--ignored` where it is.
    #[test]
    #[ignore = "needs office_seed7.json.gz (12.9 MB) from $YGG_DSG_DATA or /work/shared/data"]
    fn full_office_imports_with_paper_counts() {
        let path = data_dir().join("office_seed7.json.gz");
        assert!(
            path.exists(),
            "{} is missing: set YGG_DSG_DATA to the directory holding office_seed7.json.gz",
            path.display()
        );
        let t = Instant::now();
        let g = ygg_dsg::read_file(&path).unwrap_or_else(|e| panic!("{e}"));
        let first = t.elapsed();
        let c = g.counts();
        assert_eq!(c.nodes, 3_532);
        assert_eq!(c.edges, 11_012);
        assert_eq!(c.parent_edges, 3_531);
        assert_eq!(c.kind(NodeKind::Building), 1);
        assert_eq!(c.kind(NodeKind::Room), 9);
        assert_eq!(c.kind(NodeKind::Place), 1_130);
        assert_eq!(c.kind(NodeKind::Place2d), 1_472);
        assert_eq!(c.kind(NodeKind::Agent), 705);
        assert_eq!(c.kind(NodeKind::Object), 215);
        assert_eq!(c.mesh_vertices, 354_885);
        assert_eq!(c.mesh_faces, 677_884);
        let s = g.claim_stats().expect("mesh");
        assert_eq!(s.unclaimed, 313_522);
        assert_eq!(s.multi_claimed, 28_000);
        assert_eq!(s.claimed, 41_363);
        assert_eq!(s.total_claims, 69_363);
        assert_eq!(s.wrong_boxes, 126);
        let h = g.object_label_histogram();
        assert_eq!(h.len(), 27);
        assert_eq!((h["light"], h["shelf"], h["bulletin"]), (40, 5, 1));

        if cfg!(debug_assertions) {
            eprintln!(
                "full office import (debug build): {first:?}; run with --release for timings"
            );
            return;
        }
        let mut read = Vec::new();
        let mut parse = Vec::new();
        let mut total = Vec::new();
        for _ in 0..5 {
            let t0 = Instant::now();
            let mut t_read = Duration::ZERO;
            let mut cb = |p: ImportProgress| {
                if p.phase == ImportPhase::Parse && p.done == 0 {
                    t_read = t0.elapsed();
                }
            };
            let g2 =
                ygg_dsg::read_file_with_progress(&path, &mut cb).unwrap_or_else(|e| panic!("{e}"));
            let t_all = t0.elapsed();
            assert_eq!(g2.nodes.len(), 3_532);
            read.push(t_read);
            parse.push(t_all - t_read);
            total.push(t_all);
        }
        eprintln!(
            "full office import (release, median of 5): read+gunzip {:?}, parse+validate {:?}, total {:?}",
            median(read),
            median(parse),
            median(total)
        );
    }
}
