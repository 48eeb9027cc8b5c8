//! The Rust office generator against the files written by `gen_office_dsg.py`.

/// Named `dsg` so that `cargo test -p ygg-store dsg` selects these tests.
mod dsg {
    use std::path::{Path, PathBuf};
    use std::time::{Duration, Instant};

    use ygg_dsg::office::{OfficeParams, generate};
    use ygg_dsg::{DsgGraph, NodeKind};

    fn same_kind_of_office(generated: &DsgGraph, imported: &DsgGraph, same_faces: bool) {
        let (mut a, mut b) = (generated.counts(), imported.counts());
        if !same_faces {
            (a.mesh_faces, b.mesh_faces) = (0, 0);
        }
        assert_eq!(a, b);
        assert_eq!(generated.claim_stats(), imported.claim_stats());
        assert_eq!(generated.layers, imported.layers);
        assert_eq!(generated.labelspaces, imported.labelspaces);
        assert_eq!(
            generated.object_label_histogram(),
            imported.object_label_histogram()
        );
        // Room and building nodes are fixed by the floor plan.
        let fixed = |g: &DsgGraph| {
            g.nodes
                .iter()
                .filter(|n| matches!(n.kind, NodeKind::Room | NodeKind::Building))
                .map(|n| (n.id, n.position, n.bbox, n.name.clone(), n.parent))
                .collect::<Vec<_>>()
        };
        assert_eq!(fixed(generated), fixed(imported));
        let kinds = |g: &DsgGraph| {
            g.nodes
                .iter()
                .map(|n| (n.kind, n.layer))
                .collect::<Vec<_>>()
        };
        assert_eq!(kinds(generated), kinds(imported), "same node order");
    }

    #[test]
    fn tiny_generated_office_matches_the_tiny_fixture() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/office_tiny.json");
        let imported = ygg_dsg::read_file(path).unwrap_or_else(|e| panic!("{e}"));
        let generated = generate(OfficeParams {
            seed: 7,
            scale: 0.02,
        });
        // Below scale 1 the face target (13,558) is out of reach; face counts differ.
        same_kind_of_office(&generated, &imported, false);
    }

    #[test]
    fn full_generated_office_matches_the_full_file() {
        let dir = std::env::var_os("YGG_DSG_DATA")
            .map(PathBuf::from)
            .unwrap_or_else(|| PathBuf::from("/work/shared/data"));
        let path = dir.join("office_seed7.json.gz");
        if !path.exists() {
            eprintln!("note: {} not found, skipping", path.display());
            return;
        }
        let imported = ygg_dsg::read_file(&path).unwrap_or_else(|e| panic!("{e}"));
        let generated = generate(OfficeParams::default());
        same_kind_of_office(&generated, &imported, true);
    }

    /// Prints generation times (not asserted); meaningful with `--release`.
    #[test]
    fn generation_time() {
        let scales: &[f64] = if cfg!(debug_assertions) {
            &[1.0]
        } else {
            &[0.02, 1.0, 10.0]
        };
        for &scale in scales {
            let runs = if scale > 1.0 || cfg!(debug_assertions) {
                1
            } else {
                5
            };
            let mut t = Vec::new();
            let mut vertices = 0;
            for _ in 0..runs {
                let t0 = Instant::now();
                let g = generate(OfficeParams { seed: 7, scale });
                t.push(t0.elapsed());
                vertices = g.counts().mesh_vertices;
            }
            t.sort();
            let median: Duration = t[t.len() / 2];
            eprintln!(
                "office generate scale {scale} ({vertices} vertices, {} build): median {median:?} of {runs}",
                if cfg!(debug_assertions) {
                    "debug"
                } else {
                    "release"
                }
            );
        }
    }
}
