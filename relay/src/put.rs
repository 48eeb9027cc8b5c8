//! `ygg-relay put`: puts raw bytes on a Zenoh key (for checking what importers do with
//! foreign data on their key).

use std::io::Read;
use std::path::PathBuf;
use std::time::Duration;

use clap::Args;
use zenoh::Wait as _;

use crate::network::{NetworkArgs, SessionCloseError, SessionOpenError, close};

/// Why `put` failed.
#[derive(Debug, thiserror::Error)]
pub enum PutError {
    /// The payload could not be read.
    #[error("{what}: {source}")]
    Read {
        /// The file, or `<stdin>`.
        what: String,
        /// The I/O error.
        source: std::io::Error,
    },
    /// The Zenoh session could not be opened.
    #[error(transparent)]
    Session(#[from] SessionOpenError),
    /// Zenoh refused the put.
    #[error("--key {key:?}: {source}")]
    Put {
        /// The key.
        key: String,
        /// Zenoh's reason.
        source: zenoh::Error,
    },
    /// The session did not close cleanly.
    #[error(transparent)]
    Close(#[from] SessionCloseError),
}

/// Arguments of `ygg-relay put`.
#[derive(Args, Debug)]
pub struct PutArgs {
    /// The full Zenoh key to put on.
    #[arg(long)]
    pub key: String,
    /// File whose bytes to put; `-` or absent reads standard input.
    #[arg(long)]
    pub file: Option<PathBuf>,
    /// Milliseconds to wait for the peers to connect before putting (the output's `peers=`
    /// says how many did).
    #[arg(long, default_value_t = 1000)]
    pub settle_ms: u64,
    /// How Zenoh connects.
    #[command(flatten)]
    pub network: NetworkArgs,
}

/// Puts the bytes once and exits.
///
/// # Errors
/// An unreadable file, an invalid key, or a Zenoh session that cannot open.
pub fn run(args: &PutArgs) -> Result<(), PutError> {
    let mut payload = Vec::new();
    match &args.file {
        Some(path) if path.as_os_str() != "-" => {
            payload = std::fs::read(path).map_err(|source| PutError::Read {
                what: path.display().to_string(),
                source,
            })?;
        }
        _ => {
            std::io::stdin()
                .read_to_end(&mut payload)
                .map_err(|source| PutError::Read {
                    what: "<stdin>".to_owned(),
                    source,
                })?;
        }
    }
    let session = args.network.open(None)?;
    std::thread::sleep(Duration::from_millis(args.settle_ms));
    // A peer whose TLS handshake failed is not counted: the put then reaches nobody.
    let peers = session.info().peers_zid().wait().count();
    session
        .put(&args.key, payload.clone())
        .wait()
        .map_err(|source| PutError::Put {
            key: args.key.clone(),
            source,
        })?;
    println!("put key={} bytes={} peers={peers}", args.key, payload.len());
    Ok(close(&session)?)
}
