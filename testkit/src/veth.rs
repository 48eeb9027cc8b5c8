//! Two hosts on one machine: network namespaces joined by a veth pair, for the tests and
//! benchmarks whose processes talk across a network (the Zenoh relay).

use std::path::Path;
use std::process::Command;
use std::sync::atomic::{AtomicU32, Ordering};

/// Env var that lets a test needing network namespaces skip on a machine that cannot make
/// them (not root, no `ip`, no `CAP_SYS_ADMIN` in a container): `1` skips with a message.
/// Unset, such a test fails and says why: CI runs as root and never sets it, so a relay test
/// never passes without running there.
pub const ENV_SKIP_NETNS_TESTS: &str = "YGG_SKIP_NETNS_TESTS";

/// Two network namespaces ("hosts" 0 and 1) joined by a veth pair with a private /30 of
/// their own; both namespaces (and so the pair) are deleted on drop, also when creation
/// failed half-way.
#[derive(Debug)]
pub struct VethLink {
    ns: [String; 2],
    veth: [String; 2],
    addr: [String; 2],
}

impl VethLink {
    /// Why this process cannot create namespaces, if it cannot: not root, or no `ip`
    /// (iproute2).
    pub fn unsupported() -> Option<String> {
        if !rustix::process::geteuid().is_root() {
            return Some("not root: network namespaces need CAP_SYS_ADMIN".into());
        }
        match Command::new("ip").arg("-V").output() {
            Ok(out) if out.status.success() => None,
            _ => Some("`ip` (iproute2) is missing".into()),
        }
    }

    /// Creates the namespaces and the pair. `tag` (two letters) starts their names, which
    /// also carry this process's id and a counter, so that tests in parallel and other
    /// processes never meet; the /30 is `10.<100 + counter>.<pid / 64>.<pid % 64 * 4>`.
    ///
    /// # Errors
    /// [`VethLink::unsupported`]'s reason, or the `ip` command that failed and what it said.
    pub fn create(tag: &str) -> Result<Self, String> {
        static COUNTER: AtomicU32 = AtomicU32::new(0);
        if let Some(why) = Self::unsupported() {
            return Err(why);
        }
        let n = COUNTER.fetch_add(1, Ordering::Relaxed);
        let pid = std::process::id();
        let net = format!("10.{}.{}", 100 + n % 100, (pid / 64) % 256);
        let host = (pid % 64) * 4;
        let link = Self {
            ns: [format!("{tag}A{pid}x{n}"), format!("{tag}B{pid}x{n}")],
            veth: [format!("{tag}a{pid}x{n}"), format!("{tag}b{pid}x{n}")],
            addr: [format!("{net}.{}", host + 1), format!("{net}.{}", host + 2)],
        };
        ip(&["netns", "add", &link.ns[0]])?;
        // From here on, drop deletes what exists.
        ip(&["netns", "add", &link.ns[1]])?;
        ip(&[
            "link",
            "add",
            &link.veth[0],
            "type",
            "veth",
            "peer",
            "name",
            &link.veth[1],
        ])?;
        for side in 0..2 {
            let (ns, veth) = (&link.ns[side], &link.veth[side]);
            let cidr = format!("{}/30", link.addr[side]);
            ip(&["link", "set", veth, "netns", ns])?;
            ip(&["-n", ns, "addr", "add", &cidr, "dev", veth])?;
            ip(&["-n", ns, "link", "set", veth, "up"])?;
            ip(&["-n", ns, "link", "set", "lo", "up"])?;
        }
        Ok(link)
    }

    /// For a test: [`VethLink::create`], or `None` (after saying why) when the link cannot be
    /// made and [`ENV_SKIP_NETNS_TESTS`] is `1`.
    ///
    /// # Panics
    ///
    /// When the link cannot be made and the variable is not `1`: with the reason and the
    /// variable that skips.
    pub fn create_for_test(tag: &str) -> Option<Self> {
        match Self::create(tag) {
            Ok(link) => Some(link),
            Err(why) if std::env::var(ENV_SKIP_NETNS_TESTS).as_deref() == Ok("1") => {
                eprintln!(
                    "skipped ({ENV_SKIP_NETNS_TESTS}=1): cannot make network namespaces: {why}"
                );
                None
            }
            Err(why) => panic!(
                "cannot make the network namespaces this test needs: {why}. Run as root with \
                 iproute2 (CI does), or set {ENV_SKIP_NETNS_TESTS}=1 to skip on this machine."
            ),
        }
    }

    /// `program args` run inside host `side` (0 or 1).
    pub fn command(&self, side: usize, program: &Path, args: &[&str]) -> Command {
        let mut command = Command::new("ip");
        command
            .args(["netns", "exec", &self.ns[side]])
            .arg(program)
            .args(args);
        command
    }

    /// A Cyclone DDS configuration (the `CYCLONEDDS_URI` XML) for a participant on host
    /// `side` that discovers by unicast only: bound to host `side`'s end of the link,
    /// multicast off, its peers the unicast ports of `peers` (Cyclone tries participant
    /// indices 0 to 9 at each address), announced to them every second (Cyclone's default
    /// is 30 s: a RustDDS participant started after this one, which announces itself by
    /// multicast only, would wait that long to be found). `general` and `domain` add XML
    /// inside `<General>` and `<Domain>` (tuning: fragment sizes, watermarks).
    pub fn cyclone_unicast_config(
        &self,
        side: usize,
        peers: &[&str],
        general: &str,
        domain: &str,
    ) -> String {
        let peers: String = peers
            .iter()
            .map(|a| format!("<Peer address=\"{a}\"/>"))
            .collect();
        format!(
            "<CycloneDDS><Domain Id=\"any\"><General><Interfaces><NetworkInterface \
             name=\"{}\" multicast=\"false\"/></Interfaces><AllowMulticast>false</AllowMulticast>\
             {general}</General><Discovery><ParticipantIndex>auto</ParticipantIndex><SPDPInterval>1s</SPDPInterval><Peers>{peers}\
             </Peers></Discovery>{domain}</Domain></CycloneDDS>",
            self.veth[side]
        )
    }

    /// The name of host `side`'s end of the link (the interface to bind a stack to).
    pub fn interface(&self, side: usize) -> &str {
        &self.veth[side]
    }

    /// The address of host `side`.
    pub fn address(&self, side: usize) -> &str {
        &self.addr[side]
    }

    /// `tcp/<address of side>:<port>` (a Zenoh endpoint).
    pub fn endpoint(&self, side: usize, port: u16) -> String {
        format!("tcp/{}:{port}", self.addr[side])
    }

    /// Takes host 0's end of the link down or up.
    ///
    /// # Errors
    /// The `ip` command's failure.
    pub fn set_up(&self, up: bool) -> Result<(), String> {
        let state = if up { "up" } else { "down" };
        ip(&["-n", &self.ns[0], "link", "set", &self.veth[0], state])
    }

    /// Bytes received plus sent by host 0's end of the link, read from
    /// `/proc/<pid>/net/dev` of a process (`pid`) in host 0's namespace.
    ///
    /// # Errors
    /// If that file cannot be read or does not list the link.
    pub fn wire_bytes(&self, pid: u32) -> Result<u64, String> {
        let dev = std::fs::read_to_string(format!("/proc/{pid}/net/dev"))
            .map_err(|e| format!("/proc/{pid}/net/dev: {e}"))?;
        let line = dev
            .lines()
            .find_map(|l| l.trim_start().strip_prefix(&format!("{}:", self.veth[0])))
            .ok_or_else(|| format!("{} not in /proc/{pid}/net/dev", self.veth[0]))?;
        let fields: Vec<u64> = line
            .split_whitespace()
            .filter_map(|w| w.parse().ok())
            .collect();
        Ok(fields.first().copied().unwrap_or(0) + fields.get(8).copied().unwrap_or(0))
    }
}

impl Drop for VethLink {
    fn drop(&mut self) {
        // Deleting a namespace deletes the veth end inside it, and so the pair.
        for ns in &self.ns {
            if let Err(e) = ip(&["netns", "del", ns]) {
                eprintln!("warning: {e}");
            }
        }
    }
}

/// Runs `ip args`.
fn ip(args: &[&str]) -> Result<(), String> {
    let out = Command::new("ip")
        .args(args)
        .output()
        .map_err(|e| format!("ip {}: {e} (is iproute2 installed?)", args.join(" ")))?;
    if out.status.success() {
        Ok(())
    } else {
        Err(format!(
            "ip {}: {}",
            args.join(" "),
            String::from_utf8_lossy(&out.stderr).trim()
        ))
    }
}
