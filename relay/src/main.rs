//! `ygg-relay`: readers on other hosts through Zenoh.
//!
//! `export` follows a scene in this host's shared memory and puts each changed segment and
//! each manifest on Zenoh as the same archived bytes; `import` validates what arrives and
//! republishes complete cuts into the other host's shared memory, where readers attach as
//! to any local writer. See [`keys`] for the key layout. Links are mutual TLS with the
//! fleet's CA ([`tls`], certificates by `certs`) and only `--allow`ed certificate
//! identities exchange the scene ([`access`]); plain TCP only with `--insecure`.

mod access;
mod certs;
mod cut;
mod export;
mod import;
mod keys;
mod network;
mod put;
mod tls;

use std::process::ExitCode;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use clap::{Parser, Subcommand};

#[derive(Parser, Debug)]
#[command(
    name = "ygg-relay",
    version,
    about = "Relays a Yggdrasil scene between hosts through Zenoh"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Put a local scene on Zenoh: each changed segment and each manifest, the same bytes
    /// as in shared memory; answer queries for the current snapshot.
    ///
    /// Prints `sent generation=N ...` per snapshot, `writer gone` when the local writer
    /// exits and `peers=N` when the number of linked peers changes. Runs until
    /// SIGINT/SIGTERM.
    Export(export::ExportArgs),
    /// Republish a scene from Zenoh into local shared memory: validate every segment and
    /// manifest, publish only complete cuts, resync by query on a gap or a new exporter.
    ///
    /// Prints `published generation=N ...` per cut, `writer gone; ...` when the exporter,
    /// its writer or the link goes, `dropped key=...` for invalid data, `peers=N` when the
    /// number of linked peers changes. Runs until SIGINT/SIGTERM.
    Import(import::ImportArgs),
    /// Put raw bytes on a Zenoh key once (to check what an importer does with them).
    Put(put::PutArgs),
    /// Make a CA and a certificate per host for the relays' mutual TLS (in `--dir`; keys
    /// mode 0600; an existing CA there signs new hosts).
    Certs(certs::CertsArgs),
}

fn main() -> ExitCode {
    ygg_transport::init_iceoryx_logging();
    // Zenoh's own log, only when asked for (e.g. RUST_LOG=zenoh=debug).
    zenoh::try_init_log_from_env();
    let cli = Cli::parse();
    let _ = ygg_transport::limits::raise_open_file_limit();
    let stop = Arc::new(AtomicBool::new(false));
    let flag = Arc::clone(&stop);
    if let Err(e) = ctrlc::set_handler(move || flag.store(true, Ordering::Relaxed)) {
        eprintln!("ygg-relay: error: cannot install the signal handler: {e}");
        return ExitCode::FAILURE;
    }
    let result: Result<(), Box<dyn std::error::Error>> = match &cli.command {
        Command::Export(args) => export::run(args, &stop).map_err(Into::into),
        Command::Import(args) => import::run(args, &stop).map_err(Into::into),
        Command::Put(args) => put::run(args).map_err(Into::into),
        Command::Certs(args) => certs::run(args).map_err(Into::into),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("ygg-relay: error: {e}");
            ExitCode::FAILURE
        }
    }
}
