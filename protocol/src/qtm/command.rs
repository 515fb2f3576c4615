//! Client commands as a QTM server reads them (case-insensitive words, as QTM accepts them),
//! and the client side's command texts.

use std::net::IpAddr;

/// The components emoshift streams (a subset of QTM's), as a set.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Components {
    /// `3D`: labelled markers, x y z.
    pub d3: bool,
    /// `3DRes`: labelled markers, x y z and residual.
    pub d3_res: bool,
    /// `3DNoLabels`: markers with an id, x y z id.
    pub d3_no_labels: bool,
    /// `Timecode`: SMPTE (or IRIG, or camera time).
    pub timecode: bool,
}

impl Components {
    /// Whether no component is asked for.
    pub fn is_empty(&self) -> bool {
        !(self.d3 || self.d3_res || self.d3_no_labels || self.timecode)
    }

    /// The set from words such as `3D 3DRes Timecode`; `Err(word)` names the first component
    /// emoshift does not stream (`6D`, `Analog`, ...).
    ///
    /// # Errors
    /// The first word that is not `3D`, `3DRes`, `3DNoLabels` or `Timecode`.
    pub fn parse<'a>(words: impl Iterator<Item = &'a str>) -> Result<Components, &'a str> {
        let mut c = Components::default();
        for w in words {
            match w.to_ascii_lowercase().as_str() {
                "3d" => c.d3 = true,
                "3dres" => c.d3_res = true,
                "3dnolabels" => c.d3_no_labels = true,
                "timecode" => c.timecode = true,
                _ => return Err(w),
            }
        }
        Ok(c)
    }
}

/// Which frames a stream gets.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Rate {
    /// Every frame.
    AllFrames,
    /// At most this many frames a second.
    Frequency(u32),
    /// Every n-th frame.
    Divisor(u32),
}

/// Where a stream's frames go.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Transport {
    /// Over the command connection.
    Tcp,
    /// As UDP datagrams to this port, on this address (the client's when `None`).
    Udp {
        /// The address, when the client names one.
        ip: Option<IpAddr>,
        /// The port.
        port: u16,
    },
}

/// Which parameters `GetParameters` asks for.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ParameterSet {
    /// `General` (or `All`).
    pub general: bool,
    /// `3D` (or `All`).
    pub d3: bool,
}

/// A command from a client.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Command<'a> {
    /// `Version` (asks) or `Version major.minor` (sets).
    Version(Option<(u32, u32)>),
    /// `QTMVersion`.
    QtmVersion,
    /// `ByteOrder`.
    ByteOrder,
    /// `GetState`.
    GetState,
    /// `GetParameters ...`: what emoshift has of them; `Err(word)` for a set it has not.
    GetParameters(Result<ParameterSet, &'a str>),
    /// `GetCurrentFrame components`.
    GetCurrentFrame(Result<Components, &'a str>),
    /// `StreamFrames rate [UDP[:ip]:port] components`.
    StreamFrames {
        /// Which frames.
        rate: Rate,
        /// Where to.
        transport: Transport,
        /// What in them.
        components: Result<Components, &'a str>,
    },
    /// `StreamFrames Stop`.
    StreamStop,
    /// `Disconnect` (or `Quit`): the server closes the connection.
    Disconnect,
    /// A command QTM knows that emoshift refuses (control, capture, calibration): its name.
    Refused(&'a str),
    /// Words that make no command QTM knows, or a malformed argument.
    Unknown,
}

/// Commands emoshift refuses: they take control of a capture system it is not.
const REFUSED: &[&str] = &[
    "takecontrol",
    "releasecontrol",
    "new",
    "close",
    "start",
    "stop",
    "load",
    "save",
    "loadproject",
    "getcapturec3d",
    "getcaptureqtm",
    "getcapture",
    "trig",
    "setqtmevent",
    "event",
    "calibrate",
    "reprocess",
    "led",
];

/// Reads one command text.
pub fn parse_command(text: &str) -> Command<'_> {
    let mut words = text.split_ascii_whitespace();
    let Some(name) = words.next() else {
        return Command::Unknown;
    };
    match name.to_ascii_lowercase().as_str() {
        "version" => match words.next() {
            None => Command::Version(None),
            Some(v) => parse_version(v).map_or(Command::Unknown, |v| Command::Version(Some(v))),
        },
        "qtmversion" => Command::QtmVersion,
        "byteorder" => Command::ByteOrder,
        "getstate" => Command::GetState,
        "getparameters" => Command::GetParameters(parse_parameters(words)),
        "getcurrentframe" => Command::GetCurrentFrame(Components::parse(words)),
        "streamframes" => parse_stream(words),
        "disconnect" | "quit" => Command::Disconnect,
        _ => match REFUSED.iter().find(|r| name.eq_ignore_ascii_case(r)) {
            Some(_) => Command::Refused(name),
            None => Command::Unknown,
        },
    }
}

/// `1.25` as (1, 25).
pub fn parse_version(text: &str) -> Option<(u32, u32)> {
    let (major, minor) = text.split_once('.')?;
    Some((major.parse().ok()?, minor.parse().ok()?))
}

fn parse_parameters<'a>(words: impl Iterator<Item = &'a str>) -> Result<ParameterSet, &'a str> {
    let mut set = ParameterSet::default();
    let mut any = false;
    for w in words {
        any = true;
        match w.to_ascii_lowercase().as_str() {
            "all" => {
                set.general = true;
                set.d3 = true;
            }
            "general" => set.general = true,
            "3d" => set.d3 = true,
            _ => return Err(w),
        }
    }
    if any {
        Ok(set)
    } else {
        Err("")
    }
}

fn parse_stream<'a>(mut words: impl Iterator<Item = &'a str>) -> Command<'a> {
    let Some(first) = words.next() else {
        return Command::Unknown;
    };
    let lower = first.to_ascii_lowercase();
    let rate = if lower == "stop" {
        return Command::StreamStop;
    } else if lower == "allframes" {
        Rate::AllFrames
    } else if let Some(n) = lower.strip_prefix("frequencydivisor:") {
        match n.parse() {
            Ok(n) if n > 0 => Rate::Divisor(n),
            _ => return Command::Unknown,
        }
    } else if let Some(n) = lower.strip_prefix("frequency:") {
        match n.parse() {
            Ok(n) if n > 0 => Rate::Frequency(n),
            _ => return Command::Unknown,
        }
    } else {
        return Command::Unknown;
    };
    let mut words = words.peekable();
    let mut transport = Transport::Tcp;
    if let Some(w) = words.peek() {
        if w.get(..3).is_some_and(|p| p.eq_ignore_ascii_case("udp")) {
            match parse_udp(w) {
                Some(t) => transport = t,
                None => return Command::Unknown,
            }
            words.next();
        }
    }
    Command::StreamFrames {
        rate,
        transport,
        components: Components::parse(words),
    }
}

/// `UDP:port` or `UDP:ip:port` (`UDP` alone: port 0, the caller refuses it).
fn parse_udp(word: &str) -> Option<Transport> {
    let rest = word.get(3..)?;
    if rest.is_empty() {
        return Some(Transport::Udp { ip: None, port: 0 });
    }
    let rest = rest.strip_prefix(':')?;
    match rest.rsplit_once(':') {
        None => Some(Transport::Udp {
            ip: None,
            port: rest.parse().ok()?,
        }),
        Some((ip, port)) => Some(Transport::Udp {
            ip: Some(ip.parse().ok()?),
            port: port.parse().ok()?,
        }),
    }
}
