//! `ygg-relay certs`: a fleet's certificate authority and one certificate per host for the
//! relays' mutual TLS, made with rcgen (ECDSA P-256 keys, no hand-written crypto).
//!
//! | file in `--dir` | what | goes to |
//! |---|---|---|
//! | `ca.pem` | the CA certificate | every host (`--ca`) |
//! | `ca.key` | the CA's private key (mode 0600) | nowhere: it signs new hosts here |
//! | `<host>.pem` | the host's certificate, common name `<host>` | that host (`--cert`) |
//! | `<host>.key` | the host's private key (mode 0600) | that host only (`--private-key`) |
//!
//! A host's certificate serves both ends of a link (server and client authentication): a
//! relay may listen or connect. Its common name is the identity `--allow` names.

use std::fs::OpenOptions;
use std::io::Write as _;
use std::net::IpAddr;
use std::os::unix::fs::OpenOptionsExt as _;
use std::path::{Path, PathBuf};
use std::str::FromStr;

use clap::Args;
use rcgen::{
    BasicConstraints, CertificateParams, DistinguishedName, DnType, ExtendedKeyUsagePurpose, IsCa,
    Issuer, KeyPair, KeyUsagePurpose, SanType,
};

/// How long the CA certificate is valid: ten years, longer than any host certificate it
/// signs (`--days`).
const CA_DAYS: i64 = 3650;

/// The CA's common name.
const CA_NAME: &str = "Yggdrasil relay CA";

/// One `--host` value: the identity and the names peers reach the host by.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct HostSpec {
    /// The certificate's common name: the identity `--allow` names, and the file name.
    pub name: String,
    /// Addresses and DNS names peers connect to the host by (the name is always one).
    pub addresses: Vec<String>,
}

impl FromStr for HostSpec {
    type Err = String;

    fn from_str(spec: &str) -> Result<Self, String> {
        let (name, rest) = spec.split_once('=').unwrap_or((spec, ""));
        let plain = |s: &str| {
            !s.is_empty()
                && s.chars()
                    .all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '.')
                && !s.starts_with(['-', '.'])
        };
        if !plain(name) || name == "ca" {
            return Err(format!(
                "host name {name:?}: use letters, digits, '-' and '.' (and not \"ca\"); it is the \
                 certificate's identity and its file name"
            ));
        }
        let mut addresses = vec![name.to_owned()];
        for address in rest.split(',').filter(|a| !a.is_empty()) {
            if address.parse::<IpAddr>().is_err() && !plain(address) {
                return Err(format!(
                    "{address:?} (of host {name}) is neither an IP address nor a DNS name"
                ));
            }
            addresses.push(address.to_owned());
        }
        Ok(Self {
            name: name.to_owned(),
            addresses,
        })
    }
}

/// Arguments of `ygg-relay certs`.
#[derive(Args, Debug)]
pub struct CertsArgs {
    /// Folder for the CA and the host certificates (created if missing). A CA already
    /// there (`ca.pem` and `ca.key`) signs the new hosts' certificates.
    #[arg(long, value_name = "DIR")]
    pub dir: PathBuf,
    /// A host: its identity (the certificate's common name, what `--allow` names) and,
    /// after `=`, the IP addresses or DNS names peers connect to it by, comma-separated,
    /// e.g. `robot1=10.0.0.1`. Repeatable.
    #[arg(long = "host", value_name = "NAME[=ADDR,...]", required = true)]
    pub hosts: Vec<HostSpec>,
    /// Days the host certificates are valid.
    #[arg(long, default_value_t = 365, value_parser = clap::value_parser!(u32).range(1..=3650))]
    pub days: u32,
    /// Replace a host's existing certificate and key.
    #[arg(long)]
    pub force: bool,
}

/// Why `certs` failed.
#[derive(Debug, thiserror::Error)]
pub enum CertsError {
    /// A file or the folder could not be read or written.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file or folder.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// A host's files exist and `--force` was not given.
    #[error("{} exists: pass --force to replace it", path.display())]
    Exists {
        /// The existing file.
        path: PathBuf,
    },
    /// Only one of `ca.pem` and `ca.key` is in the folder.
    #[error("{} exists but {} does not: give a folder with both or neither", present.display(), missing.display())]
    HalfCa {
        /// The file present.
        present: PathBuf,
        /// The file missing.
        missing: PathBuf,
    },
    /// rcgen refused (an unreadable CA, say).
    #[error("{what}: {source}")]
    Certificate {
        /// What was being made or read.
        what: String,
        /// rcgen's reason.
        source: rcgen::Error,
    },
}

/// Makes (or reuses) the CA in `--dir` and writes a certificate and key per host.
///
/// # Errors
/// [`CertsError`] naming the file or host.
pub fn run(args: &CertsArgs) -> Result<(), CertsError> {
    let io = |path: &Path| {
        let path = path.to_owned();
        move |source| CertsError::Io { path, source }
    };
    std::fs::create_dir_all(&args.dir).map_err(io(&args.dir))?;
    let file = |name: &str| args.dir.join(name);
    if !args.force {
        for host in &args.hosts {
            for path in [
                file(&format!("{}.pem", host.name)),
                file(&format!("{}.key", host.name)),
            ] {
                if path.exists() {
                    return Err(CertsError::Exists { path });
                }
            }
        }
    }
    let issuer = ca(&file("ca.pem"), &file("ca.key"))?;
    let now = time::OffsetDateTime::now_utc();
    for host in &args.hosts {
        let what = || format!("certificate of host {}", host.name);
        let mut params = CertificateParams::default();
        params.distinguished_name = DistinguishedName::new();
        params
            .distinguished_name
            .push(DnType::CommonName, host.name.as_str());
        for address in &host.addresses {
            let san = match address.parse::<IpAddr>() {
                Ok(ip) => SanType::IpAddress(ip),
                Err(_) => SanType::DnsName(address.clone().try_into().map_err(|source| {
                    CertsError::Certificate {
                        what: what(),
                        source,
                    }
                })?),
            };
            params.subject_alt_names.push(san);
        }
        params.is_ca = IsCa::ExplicitNoCa;
        params.key_usages = vec![KeyUsagePurpose::DigitalSignature];
        params.extended_key_usages = vec![
            ExtendedKeyUsagePurpose::ServerAuth,
            ExtendedKeyUsagePurpose::ClientAuth,
        ];
        params.use_authority_key_identifier_extension = true;
        params.not_before = now - time::Duration::hours(1);
        params.not_after = now + time::Duration::days(i64::from(args.days));
        let key = KeyPair::generate().map_err(|source| CertsError::Certificate {
            what: what(),
            source,
        })?;
        let cert = params
            .signed_by(&key, &issuer)
            .map_err(|source| CertsError::Certificate {
                what: what(),
                source,
            })?;
        let (cert_path, key_path) = (
            file(&format!("{}.pem", host.name)),
            file(&format!("{}.key", host.name)),
        );
        write(&key_path, &key.serialize_pem(), true)?;
        write(&cert_path, &cert.pem(), true)?;
        println!(
            "host identity={} cert={} key={} names={}",
            host.name,
            cert_path.display(),
            key_path.display(),
            host.addresses.join(",")
        );
    }
    Ok(())
}

/// The CA in `cert`/`key`, made there first if neither exists.
fn ca(cert: &Path, key: &Path) -> Result<Issuer<'static, KeyPair>, CertsError> {
    let read = |path: &Path| {
        std::fs::read_to_string(path).map_err(|source| CertsError::Io {
            path: path.to_owned(),
            source,
        })
    };
    let refused = |what: &Path| {
        let what = format!("CA {}", what.display());
        move |source| CertsError::Certificate { what, source }
    };
    match (cert.exists(), key.exists()) {
        (true, true) => {
            let signing_key = KeyPair::from_pem(&read(key)?).map_err(refused(key))?;
            let issuer =
                Issuer::from_ca_cert_pem(&read(cert)?, signing_key).map_err(refused(cert))?;
            println!("ca reused cert={}", cert.display());
            Ok(issuer)
        }
        (false, false) => {
            let mut params = CertificateParams::default();
            params.distinguished_name = DistinguishedName::new();
            params.distinguished_name.push(DnType::CommonName, CA_NAME);
            params.is_ca = IsCa::Ca(BasicConstraints::Constrained(0));
            params.key_usages = vec![
                KeyUsagePurpose::KeyCertSign,
                KeyUsagePurpose::CrlSign,
                KeyUsagePurpose::DigitalSignature,
            ];
            let now = time::OffsetDateTime::now_utc();
            params.not_before = now - time::Duration::hours(1);
            params.not_after = now + time::Duration::days(CA_DAYS);
            let signing_key = KeyPair::generate().map_err(refused(key))?;
            let certificate = params.self_signed(&signing_key).map_err(refused(cert))?;
            write(key, &signing_key.serialize_pem(), false)?;
            write(cert, &certificate.pem(), false)?;
            println!(
                "ca created cert={} key={} (keep the key on this machine)",
                cert.display(),
                key.display()
            );
            Ok(Issuer::new(params, signing_key))
        }
        (present, _) => {
            let (present, missing) = if present { (cert, key) } else { (key, cert) };
            Err(CertsError::HalfCa {
                present: present.to_owned(),
                missing: missing.to_owned(),
            })
        }
    }
}

/// Writes `text` to a new file `path` readable by its owner only (0600); `replace` removes
/// an existing file first (a new file gets the mode; an old one would keep its own).
fn write(path: &Path, text: &str, replace: bool) -> Result<(), CertsError> {
    let io = |source| CertsError::Io {
        path: path.to_owned(),
        source,
    };
    if replace {
        match std::fs::remove_file(path) {
            Err(e) if e.kind() != std::io::ErrorKind::NotFound => return Err(io(e)),
            _ => {}
        }
    }
    let mut file = OpenOptions::new()
        .write(true)
        .create_new(true)
        .mode(0o600)
        .open(path)
        .map_err(io)?;
    file.write_all(text.as_bytes()).map_err(io)
}

#[cfg(test)]
mod tests {
    use std::os::unix::fs::PermissionsExt as _;

    use super::*;

    fn args(dir: &Path, hosts: &[&str]) -> CertsArgs {
        CertsArgs {
            dir: dir.to_owned(),
            hosts: hosts.iter().map(|h| h.parse().expect("host")).collect(),
            days: 30,
            force: false,
        }
    }

    #[test]
    fn host_specs_are_checked() {
        let host: HostSpec = "robot1=10.0.0.1,robot1.local".parse().expect("valid");
        assert_eq!(host.name, "robot1");
        assert_eq!(host.addresses, ["robot1", "10.0.0.1", "robot1.local"]);
        for (bad, says) in [
            ("", "host name"),
            ("ca", "not \"ca\""),
            ("../x", "host name"),
            ("r1=a b", "neither"),
        ] {
            let err = bad.parse::<HostSpec>().expect_err(bad);
            assert!(err.contains(says), "{bad}: {err}");
        }
    }

    #[test]
    fn keys_are_private_a_ca_is_reused_and_hosts_are_not_overwritten() {
        let dir = tempfile::tempdir().expect("temp dir");
        run(&args(dir.path(), &["robot1=10.0.0.1", "base"])).expect("certs");
        for name in ["ca.key", "robot1.key", "base.key"] {
            let mode = std::fs::metadata(dir.path().join(name))
                .expect(name)
                .permissions()
                .mode();
            assert_eq!(mode & 0o777, 0o600, "{name}");
        }
        let ca = std::fs::read(dir.path().join("ca.pem")).expect("ca.pem");
        run(&args(dir.path(), &["robot2"])).expect("a second host, same CA");
        assert_eq!(std::fs::read(dir.path().join("ca.pem")).expect("ca"), ca);
        let err = run(&args(dir.path(), &["robot1"])).expect_err("exists");
        assert!(err.to_string().contains("--force"), "{err}");
        std::fs::remove_file(dir.path().join("ca.key")).expect("remove");
        let err = run(&args(dir.path(), &["robot3"])).expect_err("half a CA");
        assert!(err.to_string().contains("ca.key"), "{err}");
    }
}
