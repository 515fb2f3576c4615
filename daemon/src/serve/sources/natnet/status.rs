//! What the NatNet source reports: connection, server, markersets, clock, counters; as
//! `/status` pairs (`natnet/...`).

use std::time::Duration;

use protocol::StatusValue;

/// The NatNet session as `/status` and the log show it.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct NatNetStatus {
    /// The server's command address.
    pub server: String,
    /// Connected now (a server info came and the server has not gone quiet).
    pub connected: bool,
    /// `Motive 2.1.0.0, NatNet 3.0.0.0`, once known.
    pub server_name: String,
    /// Where frames arrive (multicast group or local address), once known.
    pub data: String,
    /// Markersets streamed, comma-separated.
    pub markersets: String,
    /// Connections made (the first and every reconnect).
    pub connects: u64,
    /// Times the server was lost (silent, restarted, disconnected).
    pub disconnects: u64,
    /// NAT_FRAMEOFDATA datagrams handed on.
    pub frames: u64,
    /// Datagrams that did not decode.
    pub bad_datagrams: u64,
    /// Server clock minus local clock, µs, from the echo with the lowest round trip.
    pub clock_offset_us: Option<i64>,
    /// That echo's round trip.
    pub rtt: Option<Duration>,
    /// The capture rate the server announced.
    pub announced_rate_hz: Option<f64>,
}

impl NatNetStatus {
    /// `(name, value)` pairs for `/status/confirm`.
    pub fn pairs(&self) -> Vec<(String, StatusValue)> {
        let text = |k: &str, v: &str| (format!("natnet/{k}"), StatusValue::Text(v.to_string()));
        let int = |k: &str, v: u64| {
            (
                format!("natnet/{k}"),
                StatusValue::Int(i64::try_from(v).unwrap_or(i64::MAX)),
            )
        };
        vec![
            text("server", &self.server),
            int("connected", u64::from(self.connected)),
            text("server_name", &self.server_name),
            text("data", &self.data),
            text("markersets", &self.markersets),
            text(
                "announced_rate_hz",
                &self
                    .announced_rate_hz
                    .map_or(String::new(), |r| format!("{r:.3}")),
            ),
            int("connects", self.connects),
            int("disconnects", self.disconnects),
            int("frames", self.frames),
            int("bad_datagrams", self.bad_datagrams),
            (
                "natnet/clock_offset_us".into(),
                StatusValue::Int(self.clock_offset_us.unwrap_or(0)),
            ),
            int(
                "rtt_us",
                self.rtt
                    .map_or(0, |r| r.as_micros().try_into().unwrap_or(u64::MAX)),
            ),
        ]
    }
}
