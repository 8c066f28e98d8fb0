//! A request to stop a run cleanly: set by a signal handler (SIGINT, SIGTERM, SIGHUP) in
//! the binary, polled by the drivers between integrator steps. A stopped run finishes its
//! current step, writes its CSV row and its summary (naming the signal and the time), and
//! the process exits with 128 + the signal number, as shells and batch schedulers expect.

use std::sync::Arc;
use std::sync::atomic::{AtomicI32, Ordering};

/// SIGHUP's number (POSIX).
pub const SIGHUP: i32 = 1;
/// SIGINT's number (POSIX): Ctrl-C.
pub const SIGINT: i32 = 2;
/// SIGTERM's number (POSIX): what `kill`, `timeout`, systemd and Slurm send.
pub const SIGTERM: i32 = 15;

/// Shared stop request: 0 while none, else the number of the signal that asked for it.
/// Clones share the request.
#[derive(Debug, Clone, Default)]
pub struct StopFlag(Arc<AtomicI32>);

impl StopFlag {
    /// No stop requested.
    pub fn new() -> Self {
        Self::default()
    }

    /// Records a stop request by `signal` (a positive signal number). The first request
    /// wins; returns whether a request was already pending.
    pub fn request(&self, signal: i32) -> bool {
        self.0
            .compare_exchange(0, signal.max(1), Ordering::SeqCst, Ordering::SeqCst)
            .is_err()
    }

    /// Whether a stop was requested.
    pub fn is_set(&self) -> bool {
        self.0.load(Ordering::Relaxed) != 0
    }

    /// The signal that requested the stop, if any.
    pub fn signal(&self) -> Option<i32> {
        match self.0.load(Ordering::Relaxed) {
            0 => None,
            s => Some(s),
        }
    }

    /// The exit status of a process stopped by this request: 128 + the signal number.
    pub fn exit_status(&self) -> Option<u8> {
        self.signal().map(|s| (128 + s).clamp(0, 255) as u8)
    }
}

/// The conventional name of a signal number ("SIGTERM"), or "signal N".
pub fn signal_name(signal: i32) -> String {
    match signal {
        SIGHUP => "SIGHUP".into(),
        SIGINT => "SIGINT".into(),
        SIGTERM => "SIGTERM".into(),
        s => format!("signal {s}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn first_request_wins_and_gives_the_exit_status() {
        let f = StopFlag::new();
        assert!(!f.is_set());
        assert_eq!(f.exit_status(), None);
        let g = f.clone();
        assert!(!g.request(SIGTERM));
        assert!(f.request(SIGINT));
        assert_eq!(f.signal(), Some(SIGTERM));
        assert_eq!(f.exit_status(), Some(143));
        assert_eq!(signal_name(SIGHUP), "SIGHUP");
        assert_eq!(signal_name(9), "signal 9");
    }
}
