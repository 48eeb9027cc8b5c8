//! `ygg bridge zmq`: Spark-DSG's ZeroMQ stream (spark_dsg's `DsgSender`, Hydra's C++
//! `ZmqSender`) into a scene, through the shared core [`super::publish`].
//!
//! Like a `CONFLATE` subscriber it works on the newest frame: before decoding, it takes
//! every further message already received and keeps only the last (the skipped ones
//! are counted).
//!
//! ZeroMQ comes from the pure-Rust `zeromq` crate 0.7 (ZMTP 3 over TCP, interoperating
//! with libzmq's PUB sockets; tested against pyzmq's), only its tokio runtime and TCP
//! transport, driven by a current-thread runtime. Why not `zmq` 0.10: it binds libzmq,
//! which a fresh machine (Rust, cargo, Python, gcc) lacks, so `cargo test --workspace`
//! would need a system package first. `zeromq` has no `CONFLATE` option; draining the
//! messages already received and keeping the newest gives the same behaviour for a
//! full-state stream (the skipped ones are counted in the `update` line's `skipped`).

use std::time::Duration;

use zeromq::{Socket, SocketOptions, SocketRecv, SubSocket};

use super::publish::{PublishArgs, ScenePublisher};

/// How often the loop wakes without a message, to see signals and `--seconds` (SIGINT and
/// SIGTERM take effect within this time; each wake-up costs an idle bridge CPU).
const TICK: Duration = Duration::from_millis(500);

/// Arguments of `ygg bridge zmq`.
#[derive(clap::Parser, Debug)]
pub struct ZmqArgs {
    /// ZeroMQ endpoint of the Spark-DSG publisher, e.g. tcp://127.0.0.1:8001 (the URL
    /// given to spark_dsg's DsgSender or Hydra's ZmqSender, with the host to reach).
    #[arg(long)]
    connect: String,
    /// The scene to publish and its layout.
    #[command(flatten)]
    publish: PublishArgs,
    /// Seconds to wait for the publisher to accept the connection.
    #[arg(long, default_value_t = 30.0)]
    connect_timeout: f64,
    /// Stop after this many seconds; default: run until signalled.
    #[arg(long)]
    seconds: Option<f64>,
    /// Largest read from the socket, in bytes. The `zeromq` crate zero-fills the whole
    /// span before each read (however little arrives) and reserves a message's length
    /// plus one span, so a large span costs a memset per read and, once the buffer
    /// passes glibc's 32 MiB mmap threshold, fresh pages for every message; a small one
    /// costs more reads. Measured on the 31 MB office (one-object edits, bridge CPU):
    /// 8 MiB 634 ms, 1 MiB 434 ms, 256 KiB 287 ms, 128 KiB 279 ms per 10 s.
    #[arg(long, default_value_t = 256 << 10)]
    read_max_bytes: usize,
}

/// Runs the bridge until a signal, `--seconds`, or a fatal error.
pub fn run(args: &ZmqArgs) -> Result<(), Box<dyn std::error::Error>> {
    if !(args.connect_timeout.is_finite() && args.connect_timeout > 0.0) {
        return Err("--connect-timeout must be a positive number of seconds".into());
    }
    if args.seconds.is_some_and(|s| !(s.is_finite() && s > 0.0)) {
        return Err("--seconds must be a positive number".into());
    }
    // Checks the scene name before connecting (creating the writer checks it again).
    let mut scene = ScenePublisher::new(&args.publish, "zmq message")?;
    let rt = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()?;
    let mut options = SocketOptions::default();
    options
        .connect_timeout(Duration::from_secs_f64(args.connect_timeout))
        .read_buffer(64 * 1024, args.read_max_bytes.max(64 * 1024), 2);
    let mut socket = SubSocket::with_options(options);
    rt.block_on(async {
        socket.connect(&args.connect).await?;
        socket.subscribe("").await
    })
    .map_err(|e| format!("cannot subscribe to {}: {e}", args.connect))?;
    println!(
        "{}",
        serde_json::json!({"event": "connected", "endpoint": args.connect})
    );

    let stop = loop {
        if let Some(why) = scene.stopped() {
            break why;
        }
        if args
            .seconds
            .is_some_and(|s| scene.elapsed().as_secs_f64() >= s)
        {
            break "time limit".to_owned();
        }
        // The next message, then every one already here (keep the newest).
        let next = rt.block_on(async {
            let first = match tokio::time::timeout(TICK, socket.recv()).await {
                Err(_) => return Ok(None),
                Ok(m) => m?,
            };
            let mut newest = first;
            let mut stale = 0u64;
            while let Ok(m) = tokio::time::timeout(Duration::ZERO, socket.recv()).await {
                newest = m?;
                stale += 1;
            }
            Ok::<_, zeromq::ZmqError>(Some((newest, stale)))
        });
        match next {
            Ok(Some((message, stale))) => scene.message(message.into_vec(), stale)?,
            Ok(None) => {}
            Err(e) => {
                // The publisher went away; the socket reconnects by itself.
                eprintln!("ygg bridge zmq: receive: {e}");
                std::thread::sleep(TICK);
            }
        }
    };
    scene.finish(&stop);
    Ok(())
}
