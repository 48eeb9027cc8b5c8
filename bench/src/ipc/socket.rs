//! The Hydra-style baseline: the whole graph as a plain owned structure, serialized with
//! serde + postcard (a compact binary serde format in the spirit of bincode), sent over a
//! Unix socket, deserialized by the reader into the same owned structure.

use super::error::Res;
use super::interrupt::check_interrupted;
use serde::{Deserialize, Serialize};
use std::io::Write;
use std::os::unix::net::{UnixListener, UnixStream};
use std::path::PathBuf;
use std::time::{Duration, Instant};
use ygg_store::{FeatureRef, SceneView};

/// A scene graph as plain owned data, the way a consumer of a serialized graph holds it.
#[derive(Serialize, Deserialize, Debug, Default)]
pub struct PlainGraph {
    /// Layers with their nodes.
    pub layers: Vec<PlainLayer>,
    /// Layer DAG edges (parent, child).
    pub layer_edges: Vec<(u32, u32)>,
}

/// One layer.
#[derive(Serialize, Deserialize, Debug)]
pub struct PlainLayer {
    /// Layer id.
    pub id: u32,
    /// Layer name.
    pub name: String,
    /// Its nodes.
    pub nodes: Vec<PlainNode>,
}

/// One node with everything the store keeps about it.
#[derive(Serialize, Deserialize, Debug)]
pub struct PlainNode {
    /// Node id.
    pub id: u64,
    /// Parent (cross-layer nesting).
    pub parent: Option<u64>,
    /// Nested children.
    pub children: Vec<u64>,
    /// Geometry.
    pub points: Vec<[f32; 3]>,
    /// Bounding box, when kept.
    pub aabb: Option<[[f32; 3]; 2]>,
    /// Labels.
    pub labels: Vec<String>,
    /// Features.
    pub features: Vec<(String, PlainValue)>,
    /// Outgoing edges (target, description).
    pub edges: Vec<(u64, String)>,
}

/// A feature value.
#[derive(Serialize, Deserialize, Debug)]
pub enum PlainValue {
    /// String.
    Str(String),
    /// Integer.
    Int(i64),
    /// Float.
    Float(f64),
    /// Boolean.
    Bool(bool),
}

impl PlainGraph {
    /// Copies a scene (live or archived) into plain owned data.
    pub fn from_view<V: SceneView>(view: &V) -> Self {
        let mut g = PlainGraph::default();
        for l in view.layers() {
            for c in view.layer_children(l) {
                g.layer_edges.push((l.0, c.0));
            }
            let nodes = view
                .layer_nodes(l)
                .map(|n| PlainNode {
                    id: view.node_id(n).0,
                    parent: view.parent(n).map(|p| p.0),
                    children: view.children(n).map(|c| c.0).collect(),
                    points: view.points(n).to_vec(),
                    aabb: view.aabb(n).map(|b| [b.min, b.max]),
                    labels: view.labels(n).map(str::to_owned).collect(),
                    features: view
                        .features(n)
                        .map(|(k, v)| {
                            let v = match v {
                                FeatureRef::Str(s) => PlainValue::Str(s.to_owned()),
                                FeatureRef::Int(i) => PlainValue::Int(i),
                                FeatureRef::Float(f) => PlainValue::Float(f),
                                FeatureRef::Bool(b) => PlainValue::Bool(b),
                            };
                            (k.to_owned(), v)
                        })
                        .collect(),
                    edges: view
                        .out_edges(n)
                        .map(|e| (e.target.0, e.description.to_owned()))
                        .collect(),
                })
                .collect();
            g.layers.push(PlainLayer {
                id: l.0,
                name: view.layer_name(l).unwrap_or_default().to_owned(),
                nodes,
            });
        }
        g
    }

    /// Number of nodes.
    pub fn node_count(&self) -> usize {
        self.layers.iter().map(|l| l.nodes.len()).sum()
    }
}

/// The writer's end: a listening Unix socket in the temp dir named after a scene's
/// prefix (so [`ygg_testkit::remove_stale`] finds it after a killed run), removed on drop.
pub struct SocketServer {
    path: PathBuf,
    listener: UnixListener,
    stream: Option<UnixStream>,
}

impl SocketServer {
    /// Binds a fresh socket for `scene`.
    pub fn bind(scene: &ygg_testkit::TestScene) -> Res<Self> {
        let path = std::env::temp_dir().join(format!("{}ipcbench.sock", scene.prefix));
        let _ = std::fs::remove_file(&path);
        let listener = UnixListener::bind(&path)
            .map_err(|e| format!("cannot bind {}: {e}", path.display()))?;
        listener.set_nonblocking(true)?;
        Ok(SocketServer {
            path,
            listener,
            stream: None,
        })
    }

    /// The socket's path.
    pub fn path(&self) -> &std::path::Path {
        &self.path
    }

    /// Waits for the reader to connect.
    pub fn accept(&mut self, timeout: Duration) -> Res<()> {
        let deadline = Instant::now() + timeout;
        loop {
            check_interrupted()?;
            match self.listener.accept() {
                Ok((stream, _)) => {
                    stream.set_nonblocking(false)?;
                    self.stream = Some(stream);
                    return Ok(());
                }
                Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => {
                    if Instant::now() >= deadline {
                        return Err("the socket reader did not connect".into());
                    }
                    std::thread::sleep(Duration::from_millis(1));
                }
                Err(e) => return Err(format!("accept on {}: {e}", self.path.display()).into()),
            }
        }
    }

    /// Sends one frame: length, sequence number, bytes.
    pub fn send(&mut self, seq: u64, bytes: &[u8]) -> Res<()> {
        let stream = self.stream.as_mut().ok_or("no socket reader connected")?;
        let mut header = [0u8; 16];
        header[..8].copy_from_slice(&(bytes.len() as u64).to_le_bytes());
        header[8..].copy_from_slice(&seq.to_le_bytes());
        stream
            .write_all(&header)
            .and_then(|()| stream.write_all(bytes))
            .map_err(|e| format!("socket write: {e}").into())
    }

    /// Closes the connection (the reader then exits).
    pub fn close(&mut self) {
        self.stream = None;
    }
}

impl Drop for SocketServer {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.path);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_plain_graph_survives_postcard() {
        let (g, _) = super::super::scenes::small().unwrap();
        let plain = PlainGraph::from_view(&g);
        let bytes = postcard::to_allocvec(&plain).unwrap();
        let back: PlainGraph = postcard::from_bytes(&bytes).unwrap();
        assert_eq!(back.node_count(), g.node_count());
        assert_eq!(back.layers[0].nodes[3].points, vec![[3.0, 0.0, 1.0]]);
    }
}
