//! The QTM server's shared state, without sockets' I/O of its own: the clients (each with its
//! [`Outbox`], protocol version and stream request), the latest frame ([`Layout`]), and the
//! answers to commands as QTM gives them. The connection tasks feed it commands; the processing
//! thread feeds it frames.

use std::net::{IpAddr, SocketAddr};

use protocol::qtm::{
    encode_data_into, encode_empty_into, encode_event_into, encode_parameters_into,
    encode_text_into, parse_command, Command, Components, Event, PacketType, Parameters, Rate,
    Transport, MIN_VERSION, VERSION,
};

use super::layout::Layout;
#[cfg(test)]
use super::outbox;
use super::outbox::{Outbox, Refused};

/// A client's stream request.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StreamReq {
    /// What the frames carry.
    pub components: Components,
    /// Which frames.
    pub rate: Rate,
    /// The UDP target, or `None` for the TCP connection.
    pub udp: Option<SocketAddr>,
    /// Frames seen since the request (for the divisor) and the frequency's phase.
    pub seen: u64,
    phase: f64,
}

impl StreamReq {
    /// Whether this frame goes to the client, at the source's `rate_hz`.
    pub fn due(&mut self, rate_hz: f64) -> bool {
        self.seen += 1;
        match self.rate {
            Rate::AllFrames => true,
            Rate::Divisor(d) => (self.seen - 1) % u64::from(d) == 0,
            Rate::Frequency(n) => {
                if rate_hz <= 0.0 || f64::from(n) >= rate_hz {
                    return true;
                }
                self.phase += f64::from(n) / rate_hz;
                if self.phase >= 1.0 || self.seen == 1 {
                    self.phase = (self.phase - 1.0).max(0.0);
                    true
                } else {
                    false
                }
            }
        }
    }
}

/// One connected client.
#[derive(Debug)]
pub struct Client {
    /// The connection's id.
    pub id: u64,
    /// Where it connected from.
    pub peer: SocketAddr,
    /// The protocol version agreed.
    pub version: (u32, u32),
    /// Its stream, while it streams.
    pub stream: Option<StreamReq>,
    /// Its TCP output.
    pub outbox: Outbox,
}

/// The server's counters, in `/status` as `qtm_server/*`.
#[derive(Debug, Clone, Copy, Default)]
pub struct Counters {
    /// Connections accepted.
    pub connects: u64,
    /// Connections refused: too many clients.
    pub refused_full: u64,
    /// Connections refused: not on the allow-list.
    pub not_allowed: u64,
    /// Commands answered.
    pub commands: u64,
    /// Commands refused (control, capture, calibration) or not understood.
    pub refused_commands: u64,
    /// Packets that were oversized, malformed or of a type a client must not send.
    pub bad_packets: u64,
    /// Connections closed for sending half a packet and stalling.
    pub stalled: u64,
    /// Clients dropped for not reading.
    pub dead: u64,
    /// Frames sent (TCP and UDP).
    pub frames_sent: u64,
    /// Frames dropped because the client's TCP buffer was full or the UDP send failed.
    pub frames_dropped: u64,
    /// Discovery requests answered.
    pub discoveries: u64,
}

/// Every client, the latest frame and the counters.
#[derive(Debug, Default)]
pub struct Hub {
    /// The clients.
    pub clients: Vec<Client>,
    /// The latest frame and its labels.
    pub layout: Layout,
    /// The counters.
    pub counters: Counters,
    scratch: Vec<u8>,
}

/// What a connection does after a command.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum After {
    /// Keep reading.
    Continue,
    /// Close the connection.
    Close,
}

impl Hub {
    /// A new client: welcomed, as QTM welcomes.
    pub fn add(&mut self, id: u64, peer: SocketAddr, mut outbox: Outbox) -> After {
        encode_text_into(
            PacketType::Command,
            protocol::qtm::WELCOME,
            &mut self.scratch,
        );
        if outbox.send_reply(&self.scratch).is_err() {
            return After::Close;
        }
        self.counters.connects += 1;
        self.clients.push(Client {
            id,
            peer,
            version: VERSION,
            stream: None,
            outbox,
        });
        After::Continue
    }

    /// A client is gone.
    pub fn remove(&mut self, id: u64) {
        self.clients.retain(|c| c.id != id);
    }

    /// A packet that is not a command from client `id` (XML settings, garbage): refused.
    pub fn handle_other(&mut self, id: u64, kind: PacketType) -> After {
        self.counters.bad_packets += 1;
        let text = match kind {
            PacketType::Xml => "Setting parameters failed: emoshift's parameters are read-only",
            _ => "Parse error: send command packets (type 1)",
        };
        self.reply(id, PacketType::Error, text)
    }

    /// One command text from client `id`.
    pub fn handle_command(&mut self, id: u64, text: &str) -> After {
        self.counters.commands += 1;
        let Some(at) = self.clients.iter().position(|c| c.id == id) else {
            return After::Close;
        };
        match parse_command(text) {
            Command::Version(None) => {
                let (major, minor) = self.clients[at].version;
                self.reply(
                    id,
                    PacketType::Command,
                    &format!("Version is {major}.{minor}"),
                )
            }
            Command::Version(Some(v)) => self.set_version(at, v),
            Command::QtmVersion => {
                let text = concat!("QTM Version is emoshift ", env!("CARGO_PKG_VERSION"));
                self.reply(id, PacketType::Command, text)
            }
            Command::ByteOrder => {
                self.reply(id, PacketType::Command, "Byte order is little endian")
            }
            Command::GetState => {
                let event = if self.layout.has_frame {
                    Event::Connected
                } else {
                    Event::ConnectionClosed
                };
                encode_event_into(event, &mut self.scratch);
                self.send(at)
            }
            Command::GetParameters(Ok(set)) => {
                let p = Parameters {
                    version: self.clients[at].version,
                    frequency_hz: self.layout.rate_hz.round() as u32,
                    labels: &self.layout.labels,
                };
                encode_parameters_into(&p, set, &mut self.scratch);
                self.send(at)
            }
            Command::GetParameters(Err(what)) => self.refuse(
                id,
                &format!("Parameters {what:?} not available: emoshift has General and 3D"),
            ),
            Command::GetCurrentFrame(Ok(c)) if !c.is_empty() => {
                if self.layout.has_frame {
                    encode_data_into(&self.layout.frame(), c, &mut self.scratch);
                } else {
                    encode_empty_into(PacketType::NoMoreData, &mut self.scratch);
                }
                self.send(at)
            }
            Command::GetCurrentFrame(c) => self.refuse_components(id, c.err()),
            Command::StreamFrames {
                rate,
                transport,
                components: Ok(c),
            } if !c.is_empty() => self.start_stream(at, rate, transport, c),
            Command::StreamFrames { components, .. } => {
                self.refuse_components(id, components.err())
            }
            Command::StreamStop => {
                self.clients[at].stream = None;
                After::Continue
            }
            Command::Disconnect => After::Close,
            Command::Refused(name) => self.refuse(
                id,
                &format!(
                    "{name} refused: emoshift serves edited frames and controls no capture \
                     (no TakeControl, capture, file or calibration commands)"
                ),
            ),
            Command::Unknown => self.refuse(id, "Parse error"),
        }
    }

    fn set_version(&mut self, at: usize, v: (u32, u32)) -> After {
        let id = self.clients[at].id;
        // Any 1.x from 1.8 on: the components emoshift sends kept their layout since 1.8.
        if v < MIN_VERSION || v.0 != VERSION.0 {
            return self.refuse(id, &format!("Version {}.{} not supported", v.0, v.1));
        }
        self.clients[at].version = v;
        self.reply(
            id,
            PacketType::Command,
            &format!("Version set to {}.{}", v.0, v.1),
        )
    }

    fn start_stream(&mut self, at: usize, rate: Rate, t: Transport, c: Components) -> After {
        let peer = self.clients[at].peer;
        let udp = match t {
            Transport::Tcp => None,
            Transport::Udp { port: 0, .. } => {
                let id = self.clients[at].id;
                return self.refuse(id, "StreamFrames UDP needs a port: UDP:port");
            }
            Transport::Udp { ip, port } => {
                let ip: IpAddr = ip.unwrap_or(peer.ip());
                if ip != peer.ip() {
                    let id = self.clients[at].id;
                    return self.refuse(
                        id,
                        "StreamFrames UDP to another host refused: emoshift streams to the \
                         client's own address only",
                    );
                }
                Some(SocketAddr::new(ip, port))
            }
        };
        self.clients[at].stream = Some(StreamReq {
            components: c,
            rate,
            udp,
            seen: 0,
            phase: 0.0,
        });
        After::Continue
    }

    fn refuse_components(&mut self, id: u64, bad: Option<&str>) -> After {
        let text = match bad {
            Some(w) => format!("Component {w:?} not available: emoshift streams 3D, 3DRes, 3DNoLabels and Timecode"),
            None => "No component given: ask for 3D, 3DRes, 3DNoLabels or Timecode".to_string(),
        };
        self.refuse(id, &text)
    }

    fn refuse(&mut self, id: u64, text: &str) -> After {
        self.counters.refused_commands += 1;
        self.reply(id, PacketType::Error, text)
    }

    fn reply(&mut self, id: u64, kind: PacketType, text: &str) -> After {
        let Some(at) = self.clients.iter().position(|c| c.id == id) else {
            return After::Close;
        };
        encode_text_into(kind, text, &mut self.scratch);
        self.send(at)
    }

    /// Sends `scratch` to client `at`.
    fn send(&mut self, at: usize) -> After {
        match self.clients[at].outbox.send_reply(&self.scratch) {
            Ok(()) => After::Continue,
            Err(_) => {
                self.counters.dead += 1;
                After::Close
            }
        }
    }

    /// Tells every client the parameters changed (a stream appeared, relabelled or left).
    pub fn parameters_changed(&mut self) {
        encode_event_into(Event::CameraSettingsChanged, &mut self.scratch);
        let scratch = &self.scratch;
        let before = self.clients.len();
        self.clients
            .retain_mut(|c| c.outbox.send_reply(scratch) != Err(Refused::Dead));
        self.counters.dead += (before - self.clients.len()) as u64;
    }
}

#[cfg(test)]
mod tests;
