//! What the NatNet server counts ([`ServerCounters`]) and what it may spend on replies
//! ([`Budget`]).

use std::time::Instant;

/// Reply bytes allowed per second, over every peer.
pub const REPLY_BYTES_PER_S: f64 = 1_048_576.0;
/// Reply bytes allowed in a burst.
pub const REPLY_BURST_BYTES: f64 = 262_144.0;

/// Counters of the command channel and the frames sent.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct ServerCounters {
    /// NAT_CONNECT and NAT_DISCOVERY answered.
    pub connects: u64,
    /// Keep-alives taken.
    pub keepalives: u64,
    /// Keep-alives from peers that never connected (dropped).
    pub keepalives_unknown: u64,
    /// Model definitions sent.
    pub modeldefs: u64,
    /// Echo requests answered.
    pub echoes: u64,
    /// NAT_REQUEST strings answered.
    pub requests: u64,
    /// Requests answered with NAT_UNRECOGNIZED_REQUEST.
    pub unknown_requests: u64,
    /// NAT_DISCONNECT taken.
    pub disconnects: u64,
    /// Datagrams from peers outside the allow-list (dropped, unanswered).
    pub not_allowed: u64,
    /// Datagrams that did not decode (dropped).
    pub malformed: u64,
    /// Datagrams over [`protocol::natnet::MAX_COMMAND_LEN`] (dropped).
    pub oversized: u64,
    /// Messages only a server sends (dropped).
    pub not_commands: u64,
    /// Replies not sent because the reply budget was spent.
    pub over_budget: u64,
    /// Keep-alives refused because the client table was full.
    pub clients_full: u64,
    /// Clients whose lease ended.
    pub expired: u64,
    /// Frame datagrams sent.
    pub frames_sent: u64,
    /// Frame bytes sent.
    pub bytes_sent: u64,
    /// Frame sends that failed.
    pub send_errors: u64,
    /// Frames that could not be encoded.
    pub encode_errors: u64,
    /// Frame datagrams dropped because the data socket's send buffer was full.
    pub dropped_send_buffer: u64,
}

impl ServerCounters {
    /// Each counter by name.
    pub fn pairs(&self) -> [(&'static str, u64); 20] {
        [
            ("connects", self.connects),
            ("keepalives", self.keepalives),
            ("keepalives_unknown", self.keepalives_unknown),
            ("modeldefs", self.modeldefs),
            ("echoes", self.echoes),
            ("requests", self.requests),
            ("unknown_requests", self.unknown_requests),
            ("disconnects", self.disconnects),
            ("not_allowed", self.not_allowed),
            ("malformed", self.malformed),
            ("oversized", self.oversized),
            ("not_commands", self.not_commands),
            ("over_budget", self.over_budget),
            ("clients_full", self.clients_full),
            ("expired", self.expired),
            ("frames_sent", self.frames_sent),
            ("bytes_sent", self.bytes_sent),
            ("send_errors", self.send_errors),
            ("encode_errors", self.encode_errors),
            ("dropped_send_buffer", self.dropped_send_buffer),
        ]
    }
}

/// Spends reply bytes from a bucket refilled at a fixed rate.
#[derive(Debug, Clone)]
pub struct Budget {
    bytes: f64,
    at: Option<Instant>,
}

impl Default for Budget {
    fn default() -> Self {
        Budget {
            bytes: REPLY_BURST_BYTES,
            at: None,
        }
    }
}

impl Budget {
    /// Spends `n` bytes at `now` if the bucket holds them.
    pub fn take(&mut self, now: Instant, n: usize) -> bool {
        let elapsed = self
            .at
            .map_or(0.0, |t| now.saturating_duration_since(t).as_secs_f64());
        self.bytes = (self.bytes + elapsed * REPLY_BYTES_PER_S).min(REPLY_BURST_BYTES);
        self.at = Some(now);
        if self.bytes < n as f64 {
            return false;
        }
        self.bytes -= n as f64;
        true
    }
}
