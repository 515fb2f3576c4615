//! What the NatNet client tells the link: the server's info (connected, where frames
//! arrive), model definitions (a new [`Session`] layout), the clock offset, a version change,
//! the server lost; and the answer to `FrameRate`.

use std::net::{Ipv4Addr, SocketAddr};

use protocol::natnet::{
    decode_packet, response_code, Event, ModelDefs, NatNetVersion, Packet, ServerInfo,
};

use super::super::frames::NatNetLayout;
use super::{Link, Session};

impl Link {
    /// A 4-byte NAT_RESPONSE while `FrameRate` is unanswered: the rate, as an `f32`.
    pub(super) fn frame_rate_reply(&mut self, bytes: &[u8]) {
        let Ok(Packet::Response(payload)) = decode_packet(bytes) else {
            return;
        };
        let Some(code) = response_code(payload) else {
            return;
        };
        let hz = f64::from(f32::from_bits(code as u32));
        if hz.is_finite() && (1.0..=100_000.0).contains(&hz) {
            self.rate.1 = false;
            self.announced_rate_hz = Some(hz);
            self.status.announced_rate_hz = Some(hz);
            tracing::info!(target: "emoshift", rate_hz = hz, "natnet: the server's frame rate");
            self.update_session(|s| s.announced_rate_hz = Some(hz));
        }
    }

    /// Applies the client's events; `true` when the status changed.
    pub(super) fn drain_events(&mut self) -> bool {
        let mut changed = false;
        while let Some(event) = self.client.poll_event() {
            changed = true;
            match event {
                Event::Connected(info) => self.connected(info),
                Event::ModelDefs(defs) => self.model_defs(&defs),
                Event::Disconnected(reason) => {
                    self.status.connected = false;
                    self.status.disconnects += 1;
                    tracing::warn!(target: "emoshift", server = %self.config.server, ?reason,
                        "natnet: server lost, reconnecting; if it stays lost, check that Motive runs and streams (Settings > Streaming)");
                }
                Event::ClockOffset(est) => {
                    self.status.clock_offset_us = Some((est.offset_s * 1e6) as i64);
                    self.status.rtt = Some(est.rtt);
                    let epoch = self.epoch;
                    self.update_session(|s| s.clock = Some((epoch, est)));
                }
                Event::VersionChanged(v) => self.update_session(|s| s.layout.version = v),
            }
        }
        changed
    }

    fn connected(&mut self, info: ServerInfo) {
        self.status.connected = true;
        self.status.connects += 1;
        self.rate = (true, false);
        self.status.server_name = format!(
            "{} {}, NatNet {}",
            info.app_name,
            info.app_version.map(|v| v.to_string()).join("."),
            info.natnet_version
        );
        let announced = info.connection.and_then(|c| {
            c.multicast
                .then(|| SocketAddr::from((Ipv4Addr::from(c.multicast_group), c.data_port)))
        });
        self.status.data = match &self.data {
            Some((a, _)) => a.to_string(),
            None => "the command socket (unicast)".into(),
        };
        if let Some(addr) = self.config.data.or(announced) {
            if self.data.as_ref().map(|d| d.0) != Some(addr) {
                // Logged and shown, not fatal: the next server info tries again, and OSC
                // sources go on meanwhile.
                self.status.data = match self.bind_data(addr) {
                    Ok(()) => addr.to_string(),
                    Err(e) => {
                        tracing::error!(target: "emoshift", error = %format!("{e:#}"),
                            "natnet: no data socket");
                        format!("{addr} (cannot be opened: {e})")
                    }
                };
            }
        }
        tracing::info!(target: "emoshift", server = %self.config.server,
            name = %self.status.server_name, data = %self.status.data, "natnet: connected");
        self.info = Some(info);
    }

    fn model_defs(&mut self, defs: &ModelDefs) {
        let version = self.client.frame_version().unwrap_or(NatNetVersion::V3_0);
        let clock_hz = self
            .info
            .as_ref()
            .and_then(|i| i.connection)
            .map_or(0, |c| c.clock_frequency_hz);
        let layout = NatNetLayout::new(
            version,
            clock_hz,
            self.config.timecode_rate,
            defs,
            &self.config.naming,
            &mut self.ids,
        );
        let names: Vec<String> = layout
            .markersets
            .iter()
            .map(|m| format!("{} ({} markers)", m.name, m.labels.len()))
            .collect();
        self.status.markersets = names.join(", ");
        tracing::info!(target: "emoshift", markersets = %self.status.markersets,
            "natnet: model definitions");
        let clock = self
            .session
            .as_ref()
            .and_then(|s| s.clock)
            .or_else(|| self.client.clock().map(|est| (self.epoch, est)));
        self.session = Some(Session {
            server: self.config.server,
            layout,
            announced_rate_hz: self.announced_rate_hz,
            clock,
        });
    }

    /// The session with `f` applied (and the clock estimate, once there is one).
    fn update_session(&mut self, f: impl FnOnce(&mut Session)) {
        let clock = self.client.clock().map(|est| (self.epoch, est));
        if let Some(s) = &mut self.session {
            if s.clock.is_none() {
                s.clock = clock;
            }
            f(s);
        }
    }
}
