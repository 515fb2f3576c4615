//! A small UDP peer over the protocol crate, for interop checks against liblo and python-osc
//! (`scripts/interop-osc`). The library does no I/O; this example owns the sockets.
//!
//! ```text
//! osc_peer send-frame <addr> --frame N --time US --positions x,y,z,... [--missing i,j] [--flat]
//!                            [--compact TARGET:AMOUNT] [--parts MAX_BYTES]
//! osc_peer send-components <addr> --u a,b,... [--vmc name:index,...]
//! osc_peer recv <bind> --count N [--timeout-ms MS]
//! ```
//! `recv` prints one JSON line per message (bundles flattened) and one per rejected datagram.

use std::net::UdpSocket;
use std::time::Duration;

use protocol::*;
use rosc::{OscMessage, OscPacket, OscType};

/// The stream the example's outputs name.
const TAG: StreamTag<'static> = StreamTag {
    id: 0,
    name: "osc_peer",
};

type Res<T> = Result<T, String>;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if let Err(e) = run(&args) {
        eprintln!("osc_peer: {e}");
        std::process::exit(2);
    }
}

fn run(args: &[String]) -> Res<()> {
    match args {
        [cmd, addr, rest @ ..] if cmd == "send-frame" => send_frame(addr, rest),
        [cmd, addr, rest @ ..] if cmd == "send-components" => send_components(addr, rest),
        [cmd, bind, rest @ ..] if cmd == "recv" => recv(bind, rest),
        _ => Err("usage: osc_peer send-frame|send-components|recv ... (see the source)".into()),
    }
}

/// Value of `--name` in `rest`, if given.
fn opt<'a>(rest: &'a [String], name: &str) -> Option<&'a str> {
    rest.iter()
        .position(|a| a == name)
        .and_then(|i| rest.get(i + 1))
        .map(String::as_str)
}

fn num<T: std::str::FromStr>(rest: &[String], name: &str, default: Option<T>) -> Res<T> {
    match opt(rest, name) {
        Some(v) => v.parse().map_err(|_| format!("{name}: cannot parse {v:?}")),
        None => default.ok_or_else(|| format!("{name} is required")),
    }
}

fn list<T: std::str::FromStr>(s: &str) -> Res<Vec<T>> {
    s.split(',')
        .filter(|p| !p.is_empty())
        .map(|p| p.trim().parse().map_err(|_| format!("cannot parse {p:?}")))
        .collect()
}

fn socket(addr: &str) -> Res<UdpSocket> {
    let s = UdpSocket::bind("127.0.0.1:0").map_err(|e| format!("bind: {e}"))?;
    s.connect(addr)
        .map_err(|e| format!("connect {addr}: {e}"))?;
    Ok(s)
}

fn send(s: &UdpSocket, bytes: &[u8]) -> Res<()> {
    s.send(bytes).map(drop).map_err(|e| format!("send: {e}"))
}

fn send_frame(addr: &str, rest: &[String]) -> Res<()> {
    let positions: Vec<f32> = list(opt(rest, "--positions").unwrap_or(""))?;
    let mut frame = FrameBuf::new();
    let (fnum, time) = (
        num(rest, "--frame", Some(0))?,
        num(rest, "--time", Some(0))?,
    );
    frame
        .set_frame(fnum, time, &positions)
        .map_err(|e| e.to_string())?;
    for i in list::<usize>(opt(rest, "--missing").unwrap_or(""))? {
        frame.set_missing(i, true);
    }
    let s = socket(addr)?;
    let mut out = Vec::with_capacity(1_500);
    if let Some(max) = opt(rest, "--parts") {
        let max = max
            .parse()
            .map_err(|_| format!("--parts: cannot parse {max:?}"))?;
        let split = FlatSplit::new(max).map_err(|e| e.to_string())?;
        for p in 0..split.part_count(frame.marker_count()) {
            split
                .encode_part_into(&TAG, &frame, p, &mut out)
                .map_err(|e| e.to_string())?;
            send(&s, &out)?;
        }
        return Ok(());
    }
    if let Some(state) = opt(rest, "--compact") {
        let (target, amount) = state
            .split_once(':')
            .ok_or("--compact takes TARGET:AMOUNT")?;
        let amount = amount
            .parse()
            .map_err(|_| format!("bad amount {amount:?}"))?;
        encode_compact_into(&TAG, &frame, target, amount, &mut out).map_err(|e| e.to_string())?;
    } else if rest.iter().any(|a| a == "--flat") {
        encode_frame_flat_into(&frame, &mut out).map_err(|e| e.to_string())?;
    } else {
        encode_frame_into(&frame, &mut out).map_err(|e| e.to_string())?;
    }
    send(&s, &out)
}

fn send_components(addr: &str, rest: &[String]) -> Res<()> {
    let u: Vec<f32> = list(opt(rest, "--u").unwrap_or(""))?;
    let mut vmc = Vec::new();
    for pair in opt(rest, "--vmc")
        .unwrap_or("")
        .split(',')
        .filter(|p| !p.is_empty())
    {
        let (name, i) = pair.split_once(':').ok_or("--vmc takes name:index pairs")?;
        vmc.push((
            name.to_string(),
            i.parse::<usize>().map_err(|_| format!("bad index {i:?}"))?,
        ));
    }
    let mut out = Vec::new();
    encode_components_into(&TAG, &u, &vmc, &mut out).map_err(|e| e.to_string())?;
    send(&socket(addr)?, &out)
}

fn recv(bind: &str, rest: &[String]) -> Res<()> {
    if !bind.starts_with("127.0.0.1:") {
        return Err(format!("recv binds 127.0.0.1 only, got {bind}"));
    }
    let count: usize = num(rest, "--count", Some(1))?;
    let timeout: u64 = num(rest, "--timeout-ms", Some(5_000))?;
    let s = UdpSocket::bind(bind).map_err(|e| format!("bind {bind}: {e}"))?;
    s.set_read_timeout(Some(Duration::from_millis(timeout)))
        .map_err(|e| e.to_string())?;
    eprintln!("osc_peer: listening on {bind}");
    let mut buf = vec![0u8; 65_536];
    let mut frame = FrameBuf::new();
    for _ in 0..count {
        let n = s.recv(&mut buf).map_err(|e| format!("recv: {e}"))?;
        match messages(&buf[..n], &Limits::default()) {
            Ok(msgs) => msgs.for_each(|m| println!("{}", message_json(&m, &mut frame))),
            Err(e) => println!(
                "{{\"error\":{},\"kind\":\"{}\"}}",
                json_str(&e.to_string()),
                e.kind().as_str()
            ),
        }
    }
    Ok(())
}

fn json_str(s: &str) -> String {
    let mut out = String::from("\"");
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            c if (c as u32) < 0x20 => out.push_str(&format!("\\u{:04x}", c as u32)),
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

/// Floats as JSON: shortest round-trip text, NaN as null, infinities as strings.
fn json_f(v: f64) -> String {
    if v.is_nan() {
        "null".into()
    } else if v.is_infinite() {
        format!("\"{v}\"")
    } else {
        format!("{v:?}")
    }
}

fn json_f32(v: f32) -> String {
    if v.is_finite() {
        format!("{v:?}")
    } else {
        json_f(f64::from(v))
    }
}

fn message_json(m: &Message<'_>, frame: &mut FrameBuf) -> String {
    let tt = m
        .timetag
        .map_or("null".into(), |t| format!("[{},{}]", t.seconds, t.fraction));
    let head = format!("{{\"address\":{},\"timetag\":{tt}", json_str(m.address));
    if m.address == address::FRAME {
        return match decode_frame_into(m.bytes, frame) {
            Ok(h) => {
                let missing: Vec<String> = (0..h.marker_count)
                    .filter(|&i| frame.is_missing(i))
                    .map(|i| i.to_string())
                    .collect();
                let pos: Vec<String> = frame.positions().iter().map(|&v| json_f32(v)).collect();
                format!(
                    "{head},\"frame\":{},\"time_us\":{},\"form\":\"{:?}\",\"missing\":[{}],\"positions\":[{}]}}",
                    h.frame_number, h.capture_time_us, h.form, missing.join(","), pos.join(",")
                )
            }
            Err(e) => format!(
                "{head},\"error\":{},\"kind\":\"{}\"}}",
                json_str(&e.to_string()),
                e.kind().as_str()
            ),
        };
    }
    match decode_osc(m.bytes) {
        Ok(msg) => {
            let (types, args): (String, Vec<String>) = msg.args.iter().map(arg_json).unzip();
            let control = match Address::parse(m.address) {
                Some(Address::Control) => match decode_control(m.bytes) {
                    Ok(c) => format!(",\"control\":{}", json_str(&format!("{c:?}"))),
                    Err(e) => format!(",\"control_error\":{}", json_str(&e.to_string())),
                },
                _ => String::new(),
            };
            format!(
                "{head},\"types\":\"{types}\",\"args\":[{}]{control}}}",
                args.join(",")
            )
        }
        Err(e) => format!(
            "{head},\"error\":{},\"kind\":\"{}\"}}",
            json_str(&e.to_string()),
            e.kind().as_str()
        ),
    }
}

/// A generic message, for printing every argument: the protocol's pre-scan, then rosc.
fn decode_osc(bytes: &[u8]) -> Result<OscMessage, DecodeError> {
    check_datagram(bytes, &Limits::default())?;
    match rosc::decoder::decode_udp(bytes) {
        Ok((_, OscPacket::Message(m))) => Ok(m),
        _ => Err(DecodeError::WrongTypeTags),
    }
}

fn arg_json(a: &OscType) -> (char, String) {
    match a {
        OscType::Int(v) => ('i', v.to_string()),
        OscType::Long(v) => ('h', v.to_string()),
        OscType::Float(v) => ('f', json_f32(*v)),
        OscType::Double(v) => ('d', json_f(*v)),
        OscType::String(s) => ('s', json_str(s)),
        OscType::Blob(b) => (
            'b',
            format!(
                "\"{}\"",
                b.iter().map(|x| format!("{x:02x}")).collect::<String>()
            ),
        ),
        OscType::Time(t) => ('t', format!("[{},{}]", t.seconds, t.fractional)),
        OscType::Bool(b) => (if *b { 'T' } else { 'F' }, b.to_string()),
        OscType::Nil => ('N', "null".into()),
        OscType::Inf => ('I', "\"inf\"".into()),
        OscType::Char(c) => ('c', json_str(&c.to_string())),
        OscType::Midi(m) => (
            'm',
            format!("[{},{},{},{}]", m.port, m.status, m.data1, m.data2),
        ),
        OscType::Color(c) => (
            'r',
            format!("[{},{},{},{}]", c.red, c.green, c.blue, c.alpha),
        ),
        OscType::Array(_) => ('[', "\"array\"".into()),
    }
}
