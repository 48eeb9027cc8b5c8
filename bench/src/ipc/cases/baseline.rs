//! The ~40 MB graph through shared memory and through a Unix socket (serde + postcard).

use super::super::child::{ReaderProc, Scene};
use super::super::clock::unix_ns;
use super::super::error::Res;
use super::super::interrupt::check_interrupted;
use super::super::report::{Row, fmt_bytes, median, median_p99_us};
use super::super::scenes;
use super::super::socket::{PlainGraph, SocketServer};
use super::context::{Ctx, in_scene};
use super::drive::{ATTACH_TIMEOUT, Case, EXIT_GRACE, reader_args};
use std::time::{Duration, Instant};
use ygg_dsg::layout::Layout;
use ygg_store::SceneGraph;

/// Size of the socket-vs-shared-memory graph.
const BIG_BYTES: usize = 40_000_000;

/// The ~40 MB graph: the built-in office in chocolate layout (no indexes: exactly the
/// content the plain structure of the socket baseline carries), scaled to ~40 MB.
fn big_graph(ctx: &mut Ctx) -> Res<(SceneGraph, f64)> {
    if let Some(big) = &ctx.big {
        return Ok(big.clone());
    }
    let t = Instant::now();
    let unit = scenes::archived_bytes(&scenes::office(&ctx.office()?.0, Layout::Chocolate)?);
    let scale = (BIG_BYTES as f64 / unit as f64 * 100.0).round() / 100.0;
    let g = scenes::office(&scenes::office_dsg(scale), Layout::Chocolate)?;
    eprintln!(
        "40 MB graph: office at scale {scale} in chocolate layout, {} nodes, {} archived, built in {:.1?}",
        g.node_count(),
        fmt_bytes(scenes::archived_bytes(&g) as f64),
        t.elapsed()
    );
    ctx.big = Some((g.clone(), scale));
    Ok((g, scale))
}

pub(super) fn case_socket(ctx: &mut Ctx) -> Res<Vec<Row>> {
    let (graph, scale) = big_graph(ctx)?;
    let archived = scenes::archived_bytes(&graph);
    let plain = PlainGraph::from_view(&graph);
    let nodes = graph.node_count();
    let shm = in_scene(ctx, "shm40", |ctx, scene| {
        let mut case = Case::start(scene, graph, 64 * 1024, 1, "latency", None)?;
        let samples = ctx.plan.shm40_samples;
        let full = case.observe(&ctx.plan, 3, samples, &mut |g, i| {
            scenes::touch_all_layers(g, i)
        })?;
        let mut mover = scenes::AgentMover::new(case.w.graph())?;
        let samples = ctx.plan.office_samples / 2;
        let one = case.observe(&ctx.plan, 3, samples, &mut |g, _| mover.step(g))?;
        case.finish()?;
        Ok([
            full.annotate(
                Row::latency(
                    "shm_40MB",
                    &format!("~40 MB graph (office ×{scale}, chocolate), every layer republished → validated snapshot in 1 reader"),
                    &full.visible,
                )
                .with("archived_bytes", archived as f64),
            ),
            one.annotate(
                Row::latency(
                    "shm_40MB_layer_update",
                    "the same graph, one agent pose moved: only AGENTS republished → validated snapshot (a socket pipeline resends the whole graph for this)",
                    &one.visible,
                )
                .with("layers_sent", median(&one.layers_sent)),
            ),
        ])
    })?;
    let samples = ctx.plan.socket_samples;
    let socket = socket_baseline(&plain, samples, nodes)?;
    let [full, one] = shm;
    Ok(vec![
        full,
        one,
        socket.with("archived_bytes", archived as f64),
    ])
}

fn socket_baseline(plain: &PlainGraph, samples: usize, nodes: usize) -> Res<Row> {
    // Not an iceoryx2 reader: the scene is only used for naming.
    let scene = Scene::new("ipcb-socket");
    let mut server = SocketServer::bind(&scene)?;
    let mut args = reader_args("socket", None);
    args.extend(["--socket".to_owned(), server.path().display().to_string()]);
    let mut reader = ReaderProc::spawn("socket reader".into(), &scene, &args)?;
    server.accept(ATTACH_TIMEOUT)?;
    reader.expect("ready", Instant::now() + ATTACH_TIMEOUT)?;
    let mut latency = Vec::new();
    let mut serialize = Vec::new();
    let mut frame = 0usize;
    let warmup = 2;
    for i in 0..(warmup + samples) as u64 {
        check_interrupted()?;
        std::thread::sleep(Duration::from_millis(20));
        let t0 = unix_ns();
        let bytes = postcard::to_allocvec(plain).map_err(|e| format!("serialize: {e}"))?;
        let t1 = unix_ns();
        server.send(i, &bytes)?;
        let line = reader.expect("sock", Instant::now() + Duration::from_secs(60))?;
        let v: Vec<u64> = line
            .split_whitespace()
            .skip(1)
            .filter_map(|x| x.parse().ok())
            .collect();
        let [seq, done, got] = v[..] else {
            return Err(format!("malformed socket reader line {line:?}").into());
        };
        if seq != i || got as usize != nodes {
            return Err(format!(
                "socket reader answered frame {seq} with {got} nodes, expected frame {i} with {nodes}"
            )
            .into());
        }
        if i >= warmup as u64 {
            latency.push(done.saturating_sub(t0) as f64);
            serialize.push(t1.saturating_sub(t0) as f64);
        }
        frame = bytes.len();
    }
    server.close();
    reader.finish(EXIT_GRACE)?;
    Ok(Row::latency(
        "socket_40MB",
        "the same graph as a plain struct: serde/postcard serialize → Unix socket → deserialize into owned structs in 1 reader",
        &latency,
    )
    .with("serialize_us", median_p99_us(&serialize).0)
    .with("frame_bytes", frame as f64))
}
