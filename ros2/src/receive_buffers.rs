//! Larger receive buffers for the UDP sockets a RustDDS participant opens.
//!
//! RustDDS 0.11 opens its sockets with the system's default receive buffer
//! (`net.core.rmem_default`, 208 KiB on common Linux systems) and has no setting for it.
//! A full scene graph is one sample of tens of thousands of fragments sent in a burst; a
//! small buffer drops most of them, and the reliable protocol then repairs them over
//! heartbeat / NACK rounds (seconds for the office). Cyclone DDS asks for at least 1 MiB
//! by default (its `SocketReceiveBufferSize`); [`enlarge`] asks each socket the
//! participant opened for [`RECEIVE_BUFFER_BYTES`], beyond `net.core.rmem_max` where the
//! process may (CAP_NET_ADMIN), else up to it.

#![allow(
    unsafe_code,
    reason = "getsockopt / setsockopt on the participant's sockets: RustDDS exposes no handle to them"
)]

use std::collections::BTreeSet;
use std::os::fd::RawFd;

/// The receive buffer asked for on each of a participant's UDP sockets.
pub const RECEIVE_BUFFER_BYTES: usize = 16 << 20;

/// The file descriptors open in this process now.
pub(crate) fn open_fds() -> BTreeSet<RawFd> {
    std::fs::read_dir("/proc/self/fd")
        .map(|dir| {
            dir.filter_map(|entry| entry.ok()?.file_name().to_str()?.parse().ok())
                .collect()
        })
        .unwrap_or_default()
}

/// Asks every UDP socket among `fds` for a [`RECEIVE_BUFFER_BYTES`] receive buffer and
/// returns the smallest buffer granted (half what Linux reports, which counts its
/// bookkeeping in), comparable with [`RECEIVE_BUFFER_BYTES`]; `None` when `fds` holds no
/// UDP socket.
pub(crate) fn enlarge(fds: impl IntoIterator<Item = RawFd>) -> Option<usize> {
    let wanted = libc::c_int::try_from(RECEIVE_BUFFER_BYTES).unwrap_or(libc::c_int::MAX);
    fds.into_iter()
        .filter(|&fd| get(fd, libc::SO_TYPE) == Some(libc::SOCK_DGRAM))
        .filter_map(|fd| {
            // Beyond rmem_max needs CAP_NET_ADMIN; without it, SO_RCVBUF is capped there.
            if !set(fd, libc::SO_RCVBUFFORCE, wanted) {
                set(fd, libc::SO_RCVBUF, wanted);
            }
            get(fd, libc::SO_RCVBUF).and_then(|n| usize::try_from(n / 2).ok())
        })
        .min()
}

/// An integer socket option of `fd` at `SOL_SOCKET`; `None` for a descriptor that is no
/// socket (or was closed meanwhile).
fn get(fd: RawFd, option: libc::c_int) -> Option<libc::c_int> {
    let mut value: libc::c_int = 0;
    let mut len = std::mem::size_of::<libc::c_int>() as libc::socklen_t;
    // SAFETY: getsockopt writes at most `len` bytes (the size of `value`, which lives
    // across the call) to `&mut value` and the length to `&mut len`. `fd` is a plain
    // integer to the kernel: a descriptor that is not a socket, or no longer open, makes
    // the call fail (ENOTSOCK, EBADF) without touching memory.
    let rc = unsafe {
        libc::getsockopt(
            fd,
            libc::SOL_SOCKET,
            option,
            (&raw mut value).cast(),
            &raw mut len,
        )
    };
    (rc == 0).then_some(value)
}

/// Sets an integer socket option of `fd` at `SOL_SOCKET`; whether the kernel took it.
fn set(fd: RawFd, option: libc::c_int, value: libc::c_int) -> bool {
    // SAFETY: setsockopt reads `size_of::<c_int>()` bytes from `&value`, which lives
    // across the call; a descriptor that is no socket makes the call fail (see `get`).
    let rc = unsafe {
        libc::setsockopt(
            fd,
            libc::SOL_SOCKET,
            option,
            (&raw const value).cast(),
            std::mem::size_of::<libc::c_int>() as libc::socklen_t,
        )
    };
    rc == 0
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::os::fd::AsRawFd;

    #[test]
    fn a_new_udp_socket_gets_a_larger_buffer_and_other_descriptors_are_left_alone() {
        let udp = std::net::UdpSocket::bind("127.0.0.1:0").expect("bind");
        let tcp = std::net::TcpListener::bind("127.0.0.1:0").expect("bind");
        let default = get(udp.as_raw_fd(), libc::SO_RCVBUF).expect("a socket");
        let tcp_default = get(tcp.as_raw_fd(), libc::SO_RCVBUF).expect("a socket");
        // (Other tests of this process open and close descriptors meanwhile: no difference
        // of two listings here.)
        let open = open_fds();
        assert!(open.contains(&udp.as_raw_fd()) && open.contains(&tcp.as_raw_fd()));
        let granted = enlarge([tcp.as_raw_fd(), udp.as_raw_fd()])
            .expect("one UDP socket among the descriptors");
        assert_eq!(
            Some(2 * granted as libc::c_int),
            get(udp.as_raw_fd(), libc::SO_RCVBUF)
        );
        // At least what SO_RCVBUF alone may grant (the smaller of the wish and rmem_max);
        // more with CAP_NET_ADMIN.
        let rmem_max: usize = std::fs::read_to_string("/proc/sys/net/core/rmem_max")
            .expect("rmem_max")
            .trim()
            .parse()
            .expect("a number");
        let floor = rmem_max.min(RECEIVE_BUFFER_BYTES);
        assert!(granted >= floor, "{granted} < {floor} (default {default})");
        assert_eq!(get(tcp.as_raw_fd(), libc::SO_RCVBUF), Some(tcp_default));
        assert_eq!(enlarge([tcp.as_raw_fd()]), None);
    }
}
