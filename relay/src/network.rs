//! The Zenoh session of a relay: explicit endpoints, no multicast scouting, mutual TLS
//! unless `--insecure` ([`crate::tls`]), access control by certificate identity
//! ([`crate::access`]), and short leases and reconnect periods so that a broken link is
//! noticed and healed within about a second.

use std::path::PathBuf;
use std::time::{Duration, Instant};

use clap::Args;
use zenoh::Wait as _;

use crate::access::{Role, access_control};
use crate::keys::SceneKeys;
use crate::tls::{TlsArgs, TlsError, require_tls};

/// Reconnection settings a relay uses where its `--zenoh-config` file keeps Zenoh's defaults:
/// retry every 100-250 ms (the default backs off to 4 s), keep retrying for good, and give
/// up one attempt to open a link after 500 ms (the default: 10 s), so that an attempt whose
/// TCP SYN went out while the link was down (retransmitted after 1 s, then 3 s) is replaced
/// by a fresh one. A link on a LAN opens in a few milliseconds.
const RECONNECT: [(&str, &str); 3] = [
    (
        "connect/retry",
        "{period_init_ms: 100, period_max_ms: 250, period_increase_factor: 1.5}",
    ),
    ("connect/timeout_ms", "-1"),
    ("transport/unicast/open_timeout", "500"),
];

/// How long (µs) a reliable put may wait for room in a link's queue before Zenoh closes the
/// transport; set to half the lease, as Zenoh's defaults have it (5 s against 10 s).
///
/// Zenoh's 5 s default with a 1 s lease let a put block for 5 s on a dead link, and the
/// transport could not close meanwhile. The peer, which gave up after its 1 s lease,
/// reconnected into that half-closed transport: links that died again each second. In some
/// runs data from the exporter never reached the importer after the link came back
/// (`tests/tests/relay.rs`, about one run in ten, before this setting).
const BLOCK_LIMIT: &str = "transport/link/tx/queue/congestion_control/block/wait_before_close";

/// How a relay joins the Zenoh network (shared by `export`, `import` and `put`).
#[derive(Args, Debug, Clone)]
pub struct NetworkArgs {
    /// Zenoh endpoint to connect to, e.g. `tcp/10.0.0.1:7447` (repeatable).
    #[arg(long = "connect", value_name = "ENDPOINT")]
    pub connect: Vec<String>,
    /// Zenoh endpoint to listen on, e.g. `tcp/10.0.0.1:7447` (repeatable).
    #[arg(long = "listen", value_name = "ENDPOINT")]
    pub listen: Vec<String>,
    /// Zenoh mode: `peer`, `client` or `router`.
    #[arg(long, default_value = "peer", value_parser = ["peer", "client", "router"])]
    pub mode: String,
    /// Link lease in milliseconds: a peer silent this long is taken as gone (Zenoh's
    /// `transport/link/tx/lease`).
    #[arg(long, default_value_t = 1000, value_parser = clap::value_parser!(u64).range(100..=600_000))]
    pub lease_ms: u64,
    /// A Zenoh JSON5 configuration file applied first; the options above override it.
    #[arg(long, value_name = "FILE")]
    pub zenoh_config: Option<PathBuf>,
    /// Mutual TLS (default) or `--insecure`.
    #[command(flatten)]
    pub tls: TlsArgs,
}

/// Who may exchange what with a session: the `--allow`ed certificate identities, in the
/// role of `export` or `import`, on one scene's keys. `put` has none.
#[derive(Clone, Copy, Debug)]
pub struct Access<'a> {
    /// Export or import.
    pub role: Role,
    /// The scene's keys.
    pub keys: &'a SceneKeys,
    /// The certificate common names allowed.
    pub identities: &'a [String],
}

impl NetworkArgs {
    /// The Zenoh configuration these arguments describe. Multicast scouting and gossip are
    /// off: a relay talks only to the endpoints it is given. Every link is mutual TLS and,
    /// with `access`, only the allowed identities exchange the scene, unless `--insecure`.
    ///
    /// # Errors
    /// [`NetworkConfigError`] naming the option or file Zenoh rejected.
    pub fn config(&self, access: Option<Access<'_>>) -> Result<zenoh::Config, NetworkConfigError> {
        if self.connect.is_empty() && self.listen.is_empty() {
            return Err(NetworkConfigError::NoEndpoint);
        }
        let mut config = match &self.zenoh_config {
            Some(path) => {
                zenoh::Config::from_file(path).map_err(|source| NetworkConfigError::ConfigFile {
                    path: path.clone(),
                    source,
                })?
            }
            None => zenoh::Config::default(),
        };
        let json = |values: &[String]| {
            let quoted: Vec<String> = values.iter().map(|v| format!("{v:?}")).collect();
            format!("[{}]", quoted.join(","))
        };
        let lease = self.lease_ms;
        let settings = [
            ("mode", format!("{:?}", self.mode), "--mode"),
            ("connect/endpoints", json(&self.connect), "--connect"),
            ("listen/endpoints", json(&self.listen), "--listen"),
            ("scouting/multicast/enabled", "false".to_owned(), "scouting"),
            ("scouting/gossip/enabled", "false".to_owned(), "scouting"),
            ("transport/link/tx/lease", lease.to_string(), "--lease-ms"),
        ];
        for (key, value, option) in settings {
            // An empty list keeps what the file says.
            if value == "[]" {
                continue;
            }
            config.insert_json5(key, &value).map_err(|source| {
                NetworkConfigError::OptionRefused {
                    option,
                    key,
                    value: value.clone(),
                    source,
                }
            })?;
        }
        self.secure(&mut config, access)?;
        // Tuned for healing a link within about a second, where the file keeps Zenoh's default.
        let defaults = zenoh::Config::default();
        let block_limit = (lease * 1000 / 2).to_string();
        let tuned = RECONNECT
            .iter()
            .copied()
            .chain([(BLOCK_LIMIT, block_limit.as_str())]);
        for (key, value) in tuned {
            if config.get_json(key).ok() == defaults.get_json(key).ok() {
                config.insert_json5(key, value).map_err(|source| {
                    NetworkConfigError::TuningRefused {
                        key,
                        value: value.to_owned(),
                        source,
                    }
                })?;
            }
        }
        Ok(config)
    }

    /// Sets mutual TLS and access control, and checks that every endpoint is TLS (or warns
    /// once with `--insecure`).
    fn secure(
        &self,
        config: &mut zenoh::Config,
        access: Option<Access<'_>>,
    ) -> Result<(), NetworkConfigError> {
        let Some(files) = self.tls.files()? else {
            if access.is_some_and(|a| !a.identities.is_empty()) {
                return Err(NetworkConfigError::AllowWithoutTls);
            }
            return Ok(());
        };
        // Zenoh's default listens on plain TCP on every interface: without --listen (and a
        // file that sets it), a secure relay only connects.
        let listen = "listen/endpoints";
        if self.listen.is_empty()
            && config.get_json(listen).ok() == zenoh::Config::default().get_json(listen).ok()
        {
            config.insert_json5(listen, "[]").map_err(|source| {
                NetworkConfigError::TuningRefused {
                    key: listen,
                    value: "[]".to_owned(),
                    source,
                }
            })?;
        }
        for (key, option, given) in [
            ("connect/endpoints", "--connect", &self.connect),
            ("listen/endpoints", "--listen", &self.listen),
        ] {
            let option = if given.is_empty() {
                "--zenoh-config"
            } else {
                option
            };
            require_tls(option, &config.get_json(key).unwrap_or_default())?;
        }
        for (key, value) in files.settings() {
            config.insert_json5(key, &value).map_err(|source| {
                NetworkConfigError::OptionRefused {
                    option: "--ca, --cert, --private-key",
                    key,
                    value: value.clone(),
                    source,
                }
            })?;
        }
        if let Some(access) = access {
            if access.identities.is_empty() {
                return Err(NetworkConfigError::NoIdentity);
            }
            let setting = access_control(access.role, access.keys, access.identities);
            config
                .insert_json5("access_control", &setting)
                .map_err(|source| NetworkConfigError::OptionRefused {
                    option: "--allow",
                    key: "access_control",
                    value: setting.clone(),
                    source,
                })?;
        }
        Ok(())
    }

    /// Opens the Zenoh session; `access` as in [`config`](Self::config).
    ///
    /// # Errors
    /// [`SessionOpenError`]: the configuration problem or why Zenoh could not start (for
    /// example a `--listen` address this host does not have).
    pub fn open(&self, access: Option<Access<'_>>) -> Result<zenoh::Session, SessionOpenError> {
        let config = self.config(access)?;
        zenoh::open(config).wait().map_err(SessionOpenError::Open)
    }
}

/// Closes a Zenoh session (peers see its liveliness tokens go at once).
///
/// # Errors
/// [`SessionCloseError`] with Zenoh's reason.
pub fn close(session: &zenoh::Session) -> Result<(), SessionCloseError> {
    session.close().wait().map_err(SessionCloseError)
}

/// Prints `peers=N` when the number of Zenoh peers this session has links to changes
/// (checked at most every 100 ms): a peer the TLS handshake refused never counts.
#[derive(Debug, Default)]
pub struct PeerCount {
    last: Option<usize>,
    checked: Option<Instant>,
}

impl PeerCount {
    /// Checks the count, and prints it if it changed.
    pub fn update(&mut self, session: &zenoh::Session) {
        if self
            .checked
            .is_some_and(|at| at.elapsed() < Duration::from_millis(100))
        {
            return;
        }
        self.checked = Some(Instant::now());
        let peers = session.info().peers_zid().wait().count();
        if self.last != Some(peers) {
            self.last = Some(peers);
            println!("peers={peers}");
        }
    }
}

/// The network options do not make a Zenoh configuration.
#[derive(Debug, thiserror::Error)]
pub enum NetworkConfigError {
    /// The security options are incomplete or an endpoint is not TLS.
    #[error(transparent)]
    Tls(#[from] TlsError),
    /// Mutual TLS without `--allow`: nobody could exchange the scene.
    #[error(
        "give --allow NAME: the certificate identity (the --host name given to `ygg-relay          certs`) of each peer this relay exchanges the scene with"
    )]
    NoIdentity,
    /// `--allow` with `--insecure`: plain TCP carries no identity to check.
    #[error("--allow needs mutual TLS: plain TCP (--insecure) carries no certificate identity")]
    AllowWithoutTls,
    /// Neither `--connect` nor `--listen` was given.
    #[error("give at least one --connect or --listen endpoint (e.g. --listen tcp/10.0.0.1:7447)")]
    NoEndpoint,
    /// The `--zenoh-config` file could not be read or parsed.
    #[error("--zenoh-config {}: {source}", path.display())]
    ConfigFile {
        /// The file.
        path: PathBuf,
        /// Zenoh's reason.
        source: zenoh::Error,
    },
    /// Zenoh refused the setting an option makes.
    #[error("{option}: zenoh refused {key} = {value}: {source}")]
    OptionRefused {
        /// The option (or `scouting`).
        option: &'static str,
        /// The configuration key.
        key: &'static str,
        /// The value given.
        value: String,
        /// Zenoh's reason.
        source: zenoh::Error,
    },
    /// Zenoh refused one of the relay's reconnection settings.
    #[error("zenoh refused {key} = {value}: {source}")]
    TuningRefused {
        /// The configuration key.
        key: &'static str,
        /// The value.
        value: String,
        /// Zenoh's reason.
        source: zenoh::Error,
    },
}

/// The Zenoh session could not be opened.
#[derive(Debug, thiserror::Error)]
pub enum SessionOpenError {
    /// The options do not make a configuration.
    #[error(transparent)]
    Config(#[from] NetworkConfigError),
    /// Zenoh could not start with it.
    #[error("cannot open the zenoh session: {0}")]
    Open(#[source] zenoh::Error),
}

/// The Zenoh session did not close cleanly.
#[derive(Debug, thiserror::Error)]
#[error("closing the zenoh session: {0}")]
pub struct SessionCloseError(#[source] zenoh::Error);

#[cfg(test)]
mod tests {
    use super::*;

    fn args(connect: &[&str], listen: &[&str]) -> NetworkArgs {
        NetworkArgs {
            connect: connect.iter().map(|s| (*s).to_owned()).collect(),
            listen: listen.iter().map(|s| (*s).to_owned()).collect(),
            mode: "peer".into(),
            lease_ms: 1000,
            zenoh_config: None,
            tls: TlsArgs {
                insecure: true,
                ..TlsArgs::default()
            },
        }
    }

    #[test]
    fn endpoints_are_required_and_checked() {
        let err = args(&[], &[]).config(None).unwrap_err().to_string();
        assert!(err.contains("--connect"), "{err}");
        let err = args(&["nonsense"], &[])
            .config(None)
            .unwrap_err()
            .to_string();
        assert!(err.contains("--connect"), "{err}");
        let config = args(&["tcp/10.0.0.1:7447"], &["tcp/10.0.0.2:7447"])
            .config(None)
            .expect("valid endpoints");
        let multicast = config.get_json("scouting/multicast/enabled").expect("key");
        assert_eq!(multicast, "false");
        assert!(
            config
                .get_json("connect/endpoints")
                .expect("key")
                .contains("10.0.0.1")
        );
        let open_timeout = config
            .get_json("transport/unicast/open_timeout")
            .expect("key");
        assert_eq!(open_timeout, "500");
        let block_limit = config.get_json(BLOCK_LIMIT).expect("key");
        assert_eq!(block_limit, "500000", "half the 1000 ms lease, in µs");
    }

    #[test]
    fn a_config_file_keeps_its_own_reconnection_settings() {
        let dir = tempfile::tempdir().expect("temp dir");
        let path = dir.path().join("zenoh.json5");
        std::fs::write(&path, "{transport: {unicast: {open_timeout: 2500}}}").expect("write");
        let mut with_file = args(&["tcp/10.0.0.1:7447"], &[]);
        with_file.zenoh_config = Some(path);
        let config = with_file.config(None).expect("valid config");
        let open_timeout = config
            .get_json("transport/unicast/open_timeout")
            .expect("key");
        assert_eq!(open_timeout, "2500");
        let retry = config.get_json("connect/timeout_ms").expect("key");
        assert_eq!(retry, "-1");
    }
}
