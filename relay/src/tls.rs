//! How a relay secures its links: mutual TLS with the fleet's CA by default (both ends
//! present a certificate the CA signed, and a connecting relay checks the name it dialled
//! against the listener's certificate), plain TCP only with `--insecure`.

use std::path::{Path, PathBuf};

use clap::Args;

/// The security options of a relay (shared by `export`, `import` and `put`).
#[derive(Args, Debug, Clone, Default)]
pub struct TlsArgs {
    /// The fleet's CA certificate (PEM, `ca.pem` of `ygg-relay certs`): peers must present
    /// a certificate it signed.
    #[arg(long, value_name = "FILE")]
    pub ca: Option<PathBuf>,
    /// This host's certificate (PEM, `<host>.pem` of `ygg-relay certs`); its common name is
    /// the identity peers' `--allow` names.
    #[arg(long, value_name = "FILE")]
    pub cert: Option<PathBuf>,
    /// This host's private key (PEM, `<host>.key` of `ygg-relay certs`).
    #[arg(long, value_name = "FILE")]
    pub private_key: Option<PathBuf>,
    /// Plain TCP, no authentication and no encryption: anyone who reaches the endpoints can
    /// read the scene and put on its key. Prints a warning. For a trusted network only.
    #[arg(long, conflicts_with_all = ["ca", "cert", "private_key"])]
    pub insecure: bool,
}

/// The files of mutual TLS, each read and checked.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TlsFiles {
    ca: String,
    cert: String,
    private_key: String,
}

impl TlsArgs {
    /// The TLS files, or `None` with `--insecure` (after printing the warning).
    ///
    /// # Errors
    /// [`TlsError`]: a file missing from the options, unreadable or not PEM.
    pub fn files(&self) -> Result<Option<TlsFiles>, TlsError> {
        if self.insecure {
            eprintln!(
                "ygg-relay: warning: --insecure: plain TCP without authentication or encryption; \
                 anyone who reaches these endpoints can read the scene and put on its key"
            );
            return Ok(None);
        }
        let (Some(ca), Some(cert), Some(private_key)) = (&self.ca, &self.cert, &self.private_key)
        else {
            return Err(TlsError::Missing);
        };
        Ok(Some(TlsFiles {
            ca: pem_file("--ca", ca, "CERTIFICATE")?,
            cert: pem_file("--cert", cert, "CERTIFICATE")?,
            private_key: pem_file("--private-key", private_key, "PRIVATE KEY")?,
        }))
    }
}

impl TlsFiles {
    /// Zenoh's settings for mutual TLS on every link, listening and connecting.
    pub fn settings(&self) -> [(&'static str, String); 7] {
        let quoted = |s: &str| format!("{s:?}");
        [
            ("transport/link/tls/root_ca_certificate", quoted(&self.ca)),
            ("transport/link/tls/listen_certificate", quoted(&self.cert)),
            (
                "transport/link/tls/listen_private_key",
                quoted(&self.private_key),
            ),
            ("transport/link/tls/connect_certificate", quoted(&self.cert)),
            (
                "transport/link/tls/connect_private_key",
                quoted(&self.private_key),
            ),
            ("transport/link/tls/enable_mtls", "true".to_owned()),
            (
                "transport/link/tls/verify_name_on_connect",
                "true".to_owned(),
            ),
        ]
    }
}

/// `path` as a string Zenoh can read, checked to be a readable PEM file with a `label`
/// block (`CERTIFICATE`, or `PRIVATE KEY` also matching `EC PRIVATE KEY` and the like).
fn pem_file(option: &'static str, path: &Path, label: &'static str) -> Result<String, TlsError> {
    let bad = |reason: String| TlsError::File {
        option,
        path: path.to_owned(),
        reason,
    };
    let text = std::fs::read_to_string(path).map_err(|e| bad(e.to_string()))?;
    if !text
        .lines()
        .any(|l| l.starts_with("-----BEGIN ") && l.ends_with(&format!("{label}-----")))
    {
        return Err(bad(format!("no PEM block \"{label}\" in it")));
    }
    path.to_str()
        .map(str::to_owned)
        .ok_or_else(|| bad("the path is not UTF-8".to_owned()))
}

/// Checks that every endpoint in `endpoints` (Zenoh's JSON of a `connect/endpoints` or
/// `listen/endpoints` setting) is a TLS one.
///
/// # Errors
/// [`TlsError::PlainEndpoint`] naming the first endpoint that is not.
pub fn require_tls(option: &'static str, endpoints: &str) -> Result<(), TlsError> {
    // Endpoints are the JSON strings with a protocol (`proto/address`); a per-mode map's
    // keys ("peer", "router") have none.
    let strings = endpoints.split('"').skip(1).step_by(2);
    match strings
        .filter(|s| s.contains('/'))
        .find(|s| !s.starts_with("tls/"))
    {
        Some(endpoint) => Err(TlsError::PlainEndpoint {
            option,
            endpoint: endpoint.to_owned(),
        }),
        None => Ok(()),
    }
}

/// The security options do not make mutual TLS.
#[derive(Debug, thiserror::Error)]
pub enum TlsError {
    /// Some of `--ca`, `--cert`, `--private-key` are missing, and not `--insecure`.
    #[error(
        "links are mutual TLS by default: give --ca, --cert and --private-key (made by \
         `ygg-relay certs`), or --insecure for plain TCP on a trusted network"
    )]
    Missing,
    /// A file is unreadable or not what it should be.
    #[error("{option} {}: {reason}", path.display())]
    File {
        /// The option naming it.
        option: &'static str,
        /// The file.
        path: PathBuf,
        /// What is wrong.
        reason: String,
    },
    /// An endpoint is not TLS.
    #[error(
        "{option} {endpoint}: links are mutual TLS by default: use a tls/ endpoint (e.g. \
         tls/10.0.0.1:7447), or --insecure for plain TCP on a trusted network"
    )]
    PlainEndpoint {
        /// `--connect`, `--listen` (or `--zenoh-config` for the file's).
        option: &'static str,
        /// The endpoint.
        endpoint: String,
    },
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_tls_endpoints_pass() {
        assert!(require_tls("--listen", r#"["tls/10.0.0.1:7447"]"#).is_ok());
        assert!(require_tls("--listen", r#"{"peer":["tls/10.0.0.1:7447"]}"#).is_ok());
        assert!(require_tls("--listen", "[]").is_ok());
        let err = require_tls("--connect", r#"["tls/a:1","tcp/10.0.0.1:7447"]"#)
            .expect_err("tcp")
            .to_string();
        assert!(err.contains("--connect tcp/10.0.0.1:7447"), "{err}");
        assert!(err.contains("--insecure"), "{err}");
    }

    #[test]
    fn files_are_required_and_checked() {
        let missing = TlsArgs::default().files().expect_err("no files");
        assert!(missing.to_string().contains("--ca"), "{missing}");
        let dir = tempfile::tempdir().expect("temp dir");
        let cert = dir.path().join("c.pem");
        std::fs::write(
            &cert,
            "-----BEGIN CERTIFICATE-----\n-----END CERTIFICATE-----\n",
        )
        .expect("write");
        let args = TlsArgs {
            ca: Some(cert.clone()),
            cert: Some(cert.clone()),
            private_key: Some(cert.clone()),
            insecure: false,
        };
        let err = args.files().expect_err("a certificate as the key");
        assert!(
            err.to_string().starts_with("--private-key ")
                && err.to_string().contains("PRIVATE KEY"),
            "{err}"
        );
        let args = TlsArgs {
            ca: Some(dir.path().join("absent.pem")),
            ..args
        };
        let err = args.files().expect_err("absent");
        assert!(err.to_string().contains("--ca "), "{err}");
    }
}
