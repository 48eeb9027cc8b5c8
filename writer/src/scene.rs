//! [`SceneWriter`]: a live [`SceneGraph`] published through shared memory, one segment
//! per changed layer plus a manifest.

use std::collections::{BTreeSet, HashMap};
use std::path::PathBuf;
use std::time::Duration;
use ygg_store::snapshot::{
    MAX_LAYER_ID, MAX_PART_ROWS, MAX_POINT_CHUNK_LEN, PART_ROWS, POINT_CHUNK_LEN,
    STRUCTURE_SEGMENT_ID, SegmentCache,
};
use ygg_store::{LayerId, SceneGraph, SceneView, SnapshotError, TouchMark};
use ygg_transport::ManifestEntry;
use ygg_transport::{PublishError, PublisherBuilder, SegmentPublisher, WriterCreateError};

/// What one [`SceneWriter::publish`] sent.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PublishReport {
    /// The snapshot generation published.
    pub generation: u64,
    /// Layers of which a part was (re)published.
    pub layers_sent: usize,
    /// Parts (row chunks) of layers (re)published: a layer sends only its parts whose
    /// rows changed.
    pub parts_sent: usize,
    /// Chunks (re)published: point chunks whose points changed, and layer index trees
    /// built anew.
    pub chunks_sent: usize,
    /// Layers left as they were.
    pub layers_unchanged: usize,
    /// Bytes archived into shared memory (layer segments, chunks and manifest).
    pub bytes_sent: usize,
    /// Of `bytes_sent`, the point and tree chunks'.
    pub chunk_bytes_sent: usize,
    /// Of `bytes_sent`, the manifest's (store manifest and transport prefix).
    pub manifest_bytes_sent: usize,
    /// Segments the cut names (every layer's parts and chunks).
    pub segments: usize,
}

/// Owns a live scene graph and publishes it: on [`SceneWriter::publish`] each layer whose
/// generation changed since its last publish is archived straight into a loaned
/// shared-memory sample, then the manifest names the new cut.
///
/// ```no_run
/// # use ygg_writer::SceneWriter;
/// # use ygg_store::{SceneGraph, NodeId};
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// let mut writer = SceneWriter::builder("office").max_readers(8).create(SceneGraph::new())?;
/// let rooms = writer.graph_mut().add_layer("rooms")?;
/// writer.graph_mut().add_node(NodeId(1), rooms)?;
/// writer.publish()?; // readers now see the room
/// # Ok(()) }
/// ```
pub struct SceneWriter {
    graph: SceneGraph,
    /// The segments and manifest last published, rebuilt incrementally.
    segments: SegmentCache,
    publisher: SegmentPublisher,
    /// Ids of the segments (parts, point and tree chunks) of the last published cut.
    published_segments: BTreeSet<u64>,
    /// Each layer's generation as last published.
    published_generation: HashMap<LayerId, u64>,
    /// What the last successful publish left for the next one to patch.
    last_cut: Option<LastCut>,
    generation: u64,
}

/// The last published cut, as the next publish patches it when the graph's structure
/// held.
struct LastCut {
    /// The graph's structure generation it was published at.
    structure: u64,
    /// The graph's touch mark taken as it began: layers touched since may have changed.
    mark: TouchMark,
    /// Its manifest entries, ascending by segment id.
    entries: Vec<ManifestEntry>,
}

/// Configures and creates a [`SceneWriter`]; see [`SceneWriter::builder`].
#[derive(Debug, Clone)]
pub struct SceneWriterBuilder {
    publisher: PublisherBuilder,
    max_layers: Option<usize>,
    point_chunk_len: usize,
    part_rows: usize,
}

/// Least room for more layers a writer gets by default ([`SceneWriterBuilder::max_layers`]).
pub const MIN_DEFAULT_MAX_LAYERS: usize = 256;

/// The layer bound of a writer created on a graph of `layers` layers when none is set: room
/// for a quarter more segments and at least 256 more (a layer that grows over a mission
/// is split into parts: about one per 16 × [`MAX_PART_ROWS`] rows of its history, one
/// per [`MAX_PART_ROWS`] of the rows changed in the last 1,024 updates, and a few; the
/// demo's stream goes from 74 to 88 segments over 100,000 ticks; edits and removals
/// split a part into at most 32 pieces at a time), rounded up to a multiple of 64, at most
/// [`ygg_transport::protocol::MAX_LAYERS`]. Tight on purpose: attaching to the 103-room
/// office (418 layers) took 44 ms at a bound of 896 and 34 ms at 512.
pub fn default_max_layers(layers: usize) -> usize {
    layers
        .saturating_add((layers / 4).max(MIN_DEFAULT_MAX_LAYERS))
        .min(ygg_transport::protocol::MAX_LAYERS)
        .next_multiple_of(64)
}

impl SceneWriterBuilder {
    /// Most readers attached at once (default
    /// [`ygg_transport::service::DEFAULT_MAX_READERS`]). Each costs shared memory for the
    /// samples it may hold.
    pub fn max_readers(mut self, value: usize) -> Self {
        self.publisher = self.publisher.max_readers(value);
        self
    }

    /// Most segments a snapshot may have while this writer publishes it: its layers' parts
    /// plus their point and tree chunks ([`Self::point_chunk_len`]). Default: a quarter
    /// more than the graph given to [`create`](Self::create) takes, and at least 256 more;
    /// see [`default_max_layers`].
    /// A publish of more fails with [`PublishError::TooManyLayers`]. The bound sizes the
    /// shared-memory pool and what every reader initialises when it attaches (attaching to
    /// the office took 15 ms at 128 and 25 ms at 512), so set it for a scene that is
    /// created small and grows, and leave it otherwise.
    pub fn max_layers(mut self, value: usize) -> Self {
        self.max_layers = Some(value);
        self
    }

    /// Points per chunk of a chunked layer (default [`POINT_CHUNK_LEN`]; rounded up to a
    /// power of two, at most [`ygg_store::snapshot::MAX_POINT_CHUNK_LEN`]). A layer of
    /// more points publishes its point column as chunks, each resent only when its points
    /// change: appending to a mesh resends the last chunk, not the layer. Smaller chunks
    /// resend less per change but add segments to every cut.
    pub fn point_chunk_len(mut self, value: usize) -> Self {
        self.point_chunk_len = value.clamp(1, MAX_POINT_CHUNK_LEN).next_power_of_two();
        self
    }

    /// Rows the newest part of a layer takes before a new part starts (default
    /// [`PART_ROWS`]; at least 1): appending a node resends at most this many rows of its
    /// layer. Sealed parts merge up to [`MAX_PART_ROWS`] rows.
    pub fn part_rows(mut self, value: usize) -> Self {
        self.part_rows = value.max(1);
        self
    }

    /// Initial capacity of a layer's shared-memory segment; iceoryx2 grows it in
    /// power-of-two steps (default [`ygg_transport::DEFAULT_INITIAL_SEGMENT_BYTES`]).
    pub fn initial_segment_bytes(mut self, value: usize) -> Self {
        self.publisher = self.publisher.initial_segment_bytes(value);
        self
    }

    /// The shared-memory file system checked for free space before each write (default
    /// `/dev/shm`).
    pub fn shm_dir(mut self, path: impl Into<PathBuf>) -> Self {
        self.publisher = self.publisher.shm_dir(path);
        self
    }

    /// The iceoryx2 file-name prefix; overrides
    /// [`ygg_transport::service::ENV_IOX2_PREFIX`]. Readers must use the same one.
    pub fn iceoryx_prefix(mut self, prefix: &str) -> Self {
        self.publisher = self.publisher.iceoryx_prefix(prefix);
        self
    }

    /// How often the writer's helper thread asks iceoryx2 whether a reader it cannot watch
    /// through a pidfd (another pid namespace) is alive (default 200 ms); the exit of any
    /// other reader wakes it at once.
    pub fn liveness_interval(mut self, value: Duration) -> Self {
        self.publisher = self.publisher.liveness_interval(value);
        self
    }

    /// Creates the scene's services and takes ownership of `graph` (nothing is published
    /// until [`SceneWriter::publish`]).
    ///
    /// # Errors
    /// As [`PublisherBuilder::create`]: an invalid name, or a live writer on this scene.
    pub fn create(self, graph: SceneGraph) -> Result<SceneWriter, WriterCreateError> {
        let max_layers = self
            .max_layers
            .unwrap_or_else(|| default_max_layers(graph.snapshot_segments(self.point_chunk_len)));
        Ok(SceneWriter {
            graph,
            segments: SegmentCache::with_point_chunk_len(self.point_chunk_len)
                .with_part_rows(self.part_rows, MAX_PART_ROWS.max(self.part_rows)),
            // One more for the structure segment every cut names.
            publisher: self.publisher.max_segments(max_layers + 1).create()?,
            published_segments: BTreeSet::new(),
            published_generation: HashMap::new(),
            last_cut: None,
            generation: 0,
        })
    }
}

impl SceneWriter {
    /// A builder for the writer of `scene` (ASCII letters, digits, `-`, `_`, `.`; at most
    /// [`ygg_transport::service::MAX_SCENE_NAME_LEN`] bytes), with default settings.
    pub fn builder(scene: &str) -> SceneWriterBuilder {
        SceneWriterBuilder {
            publisher: PublisherBuilder::new(scene),
            max_layers: None,
            point_chunk_len: POINT_CHUNK_LEN,
            part_rows: PART_ROWS,
        }
    }

    /// Most segments (parts, point and tree chunks) a publish may name, the structure
    /// segment aside ([`SceneWriterBuilder::max_layers`]).
    pub fn max_layers(&self) -> usize {
        // The publisher's bound has room for the structure segment besides.
        self.publisher.max_segments().saturating_sub(1)
    }

    /// The live graph.
    pub fn graph(&self) -> &SceneGraph {
        &self.graph
    }

    /// The live graph, for mutations; readers see them at the next publish.
    pub fn graph_mut(&mut self) -> &mut SceneGraph {
        &mut self.graph
    }

    /// The transport publisher (waiting, connection updates).
    pub fn publisher(&self) -> &SegmentPublisher {
        &self.publisher
    }

    /// The generation of the last published snapshot (0 before the first).
    pub fn generation(&self) -> u64 {
        self.generation
    }

    /// Publishes every changed layer and then the manifest of the new cut, stamped with
    /// the time this call began (so readers' publish-to-visible latency includes the
    /// archiving). Segments are built incrementally
    /// ([`SegmentCache::layer_segment`]): a small change to a large layer re-archives
    /// that layer but rebuilds only the changed rows.
    ///
    /// # Errors
    /// [`PublishError::SharedMemoryFull`] before anything is written when `/dev/shm`
    /// lacks room, [`PublishError::TooManyLayers`] (also before anything is written) when
    /// the graph has more layers than [`max_layers`](Self::max_layers), and the other
    /// transport errors. On error the previous snapshot stays
    /// the current one for readers.
    pub fn publish(&mut self) -> Result<PublishReport, PublishError> {
        let structure = self.graph.structure_generation();
        let mark = self.graph.touch_mark();
        // With the structure unchanged since the last cut, the touch log names the
        // changed layers and the last cut's entries are patched: O(changed), not
        // O(layers). Otherwise (first publish, a layer or DAG edge added or removed, the
        // last publish failed) every layer is looked at. Taken out, so that a failed
        // publish leaves none and the next one looks at every layer.
        let last = self.last_cut.take().filter(|c| c.structure == structure);
        let touched = last
            .as_ref()
            .and_then(|c| self.graph.layers_touched_since(c.mark));
        let incremental = touched.is_some();
        let candidates = match touched {
            Some(touched) => touched,
            None => self.graph.layers().collect(),
        };
        if let Some(layer) = candidates.iter().find(|l| l.0 > MAX_LAYER_ID) {
            return Err(PublishError::ReservedLayerId(u64::from(layer.0)));
        }
        let changed: Vec<LayerId> = candidates
            .into_iter()
            .filter(|l| {
                self.published_generation.get(l) != self.graph.layer_generation(*l).as_ref()
            })
            .collect();
        // Changed layers are brought up to date first, so that the cut's segments are
        // counted (a layer's parts and chunks may have changed) before any goes out.
        let mut reshaped = false;
        for layer in &changed {
            reshaped |= self
                .segments
                .published_layer(&mut self.graph, *layer)
                .reshaped();
        }
        let layer_count = self.graph.layer_count();
        let segments = layer_count + self.segments.extra_segments();
        if segments > self.max_layers() {
            // Refused before any segment goes out, so readers see nothing of this cut.
            return Err(PublishError::TooManyLayers {
                count: segments,
                max: self.max_layers(),
            });
        }
        self.publisher.start_cut();
        let mut report = PublishReport {
            layers_unchanged: layer_count - changed.len(),
            ..PublishReport::default()
        };
        // Every segment the loop looks at, sent or not: the entries a patched cut updates.
        let mut looked_at = Vec::new();
        for layer in &changed {
            let published = self.segments.published(*layer).expect("brought up to date");
            report.layers_sent += 1;
            // After a publish that went out, only the parts that changed since may differ
            // from what readers hold; otherwise every part is looked at.
            let parts: Vec<_> = if incremental {
                published.changed_parts().collect()
            } else {
                published.parts().iter().collect()
            };
            for part in parts {
                let id = part.segment_id();
                looked_at.push((id, part.segment.generation));
                if self.publisher.layer_generation(id) != Some(part.segment.generation) {
                    let len = part.segment.archived_len();
                    self.publisher
                        .try_publish_layer(id, part.segment.generation, len, |buf| {
                            part.segment.archive_into(buf).map(|_| ())
                        })?;
                    report.parts_sent += 1;
                    report.bytes_sent += len;
                }
                for (index, (id, chunk_generation)) in part.chunks().enumerate() {
                    looked_at.push((id, chunk_generation));
                    if self.publisher.layer_generation(id) != Some(chunk_generation) {
                        let chunk = part.chunk(index);
                        let len = chunk.archived_len();
                        send_chunk(
                            &mut self.publisher,
                            &mut report,
                            id,
                            chunk_generation,
                            len,
                            |buf| chunk.archive_into(buf),
                        )?;
                    }
                }
                for (id, tree_generation, chunk) in part.tree_chunks() {
                    looked_at.push((id, tree_generation));
                    if self.publisher.layer_generation(id) == Some(tree_generation) {
                        continue;
                    }
                    let len = chunk.archived_len();
                    send_chunk(
                        &mut self.publisher,
                        &mut report,
                        id,
                        tree_generation,
                        len,
                        |buf| chunk.archive_into(buf),
                    )?;
                }
            }
        }
        let entries = match last {
            Some(mut cut) if !reshaped => {
                patch_entries(&mut cut.entries, &looked_at);
                cut.entries
            }
            _ => self.cut_entries(),
        };
        let generation = self.generation + 1;
        let cut = self.segments.manifest_bytes(
            &self.graph,
            generation,
            incremental.then_some(changed.as_slice()),
        );
        let (manifest, len) = (cut.manifest, cut.manifest.len());
        let structure_generation = cut.structure.generation;
        if self.publisher.layer_generation(STRUCTURE_SEGMENT_ID) != Some(structure_generation) {
            let structure_len = cut.structure_bytes.len();
            self.publisher.try_publish_layer(
                STRUCTURE_SEGMENT_ID,
                structure_generation,
                structure_len,
                |buf| {
                    buf[..structure_len].copy_from_slice(cut.structure_bytes);
                    Ok::<(), SnapshotError>(())
                },
            )?;
            report.bytes_sent += structure_len;
            report.manifest_bytes_sent += structure_len;
        }
        let mut entries = entries;
        match entries.binary_search_by_key(&STRUCTURE_SEGMENT_ID, |e| e.layer_id) {
            Ok(i) => entries[i].generation = structure_generation,
            Err(i) => entries.insert(
                i,
                ManifestEntry {
                    layer_id: STRUCTURE_SEGMENT_ID,
                    generation: structure_generation,
                },
            ),
        }
        self.publisher
            .try_publish_manifest(generation, &entries, len, |buf| {
                buf[..len].copy_from_slice(manifest);
                Ok::<(), SnapshotError>(())
            })?;
        self.generation = generation;
        report.generation = generation;
        let manifest_len = len + ygg_transport::protocol::manifest_prefix_len(entries.len());
        report.bytes_sent += manifest_len;
        report.manifest_bytes_sent += manifest_len;
        report.segments = entries.len();
        for layer in &changed {
            let g = self.graph.layer_generation(*layer).expect("listed layer");
            self.published_generation.insert(*layer, g);
        }
        self.last_cut = Some(LastCut {
            structure,
            mark,
            entries,
        });
        Ok(report)
    }

    /// The entries of the cut, built afresh from every layer (ascending by segment id:
    /// parts, then point chunks, then tree chunks), retiring the ids of the last cut that
    /// are gone.
    fn cut_entries(&mut self) -> Vec<ManifestEntry> {
        let mut entries: Vec<ManifestEntry> = self
            .graph
            .layers()
            .filter_map(|l| self.segments.published(l))
            .flat_map(|published| published.segments())
            .map(|(layer_id, generation)| ManifestEntry {
                layer_id,
                generation,
            })
            .collect();
        entries.sort_unstable_by_key(|e| e.layer_id);
        let mut live: BTreeSet<u64> = entries.iter().map(|e| e.layer_id).collect();
        // The structure's entry is set by the publish.
        live.insert(STRUCTURE_SEGMENT_ID);
        for gone in self.published_segments.difference(&live) {
            self.publisher.retire_layer(*gone);
        }
        self.published_segments = live;
        let graph = &self.graph;
        self.published_generation
            .retain(|layer, _| graph.layer_generation(*layer).is_some());
        entries
    }
}

/// Sets the generation of each segment of `segments` (id, generation) in the last cut's
/// entries (ascending by segment id; the layers' shapes are unchanged, so every id is
/// there).
fn patch_entries(entries: &mut [ManifestEntry], segments: &[(u64, u64)]) {
    for &(id, generation) in segments {
        if let Ok(i) = entries.binary_search_by_key(&id, |e| e.layer_id) {
            entries[i].generation = generation;
        }
    }
}

/// Sends chunk `id` at `generation`, `len` bytes that `archive` writes, and counts it in
/// `report`.
fn send_chunk(
    publisher: &mut SegmentPublisher,
    report: &mut PublishReport,
    id: u64,
    generation: u64,
    len: usize,
    archive: impl FnOnce(&mut [u8]) -> Result<usize, SnapshotError>,
) -> Result<(), PublishError> {
    publisher.try_publish_layer(id, generation, len, |buf| archive(buf).map(|_| ()))?;
    report.chunks_sent += 1;
    report.bytes_sent += len;
    report.chunk_bytes_sent += len;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_default_layer_bound_leaves_a_quarter_and_at_least_256_more_in_steps_of_64() {
        assert_eq!(default_max_layers(0), 256);
        assert_eq!(default_max_layers(1), 320);
        assert_eq!(default_max_layers(42), 320);
        assert_eq!(default_max_layers(64), 320);
        assert_eq!(default_max_layers(65), 384);
        assert_eq!(default_max_layers(418), 704);
        assert_eq!(default_max_layers(4000), 4096);
        assert_eq!(
            default_max_layers(usize::MAX),
            ygg_transport::protocol::MAX_LAYERS
        );
    }
}
