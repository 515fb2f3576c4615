//! One config value at a time: addresses, the control secret, a performer, a `--send` target.
//! Each error names the key it came from, so a bad value is found without reading the source.

use std::net::SocketAddr;

use protocol::Profile;

use super::{ConfigError, PerformerConfig, RawPerformer};

pub(super) fn check(
    key: &'static str,
    ok: bool,
    value: impl std::fmt::Display,
    range: &'static str,
) -> Result<(), ConfigError> {
    match ok {
        true => Ok(()),
        false => Err(ConfigError::Range {
            key,
            value: value.to_string(),
            range,
        }),
    }
}

pub(super) fn addr(
    key: &'static str,
    v: Option<String>,
    default: &str,
) -> Result<SocketAddr, ConfigError> {
    let v = v.unwrap_or_else(|| default.to_string());
    v.parse::<SocketAddr>()
        .map_err(|_| ConfigError::Address { key, value: v })
}

pub(super) fn secret(s: Option<String>) -> Result<Option<String>, ConfigError> {
    match s {
        Some(s) if s.is_empty() || s.len() > protocol::MAX_NAME_BYTES || s.contains('\0') => {
            Err(ConfigError::Range {
                key: "control_secret",
                value: format!("of {} bytes", s.len()),
                range: "1 to 256 bytes, no NUL",
            })
        }
        other => Ok(other),
    }
}

pub(super) fn performer(p: RawPerformer) -> Result<PerformerConfig, ConfigError> {
    let source = p
        .source
        .map(|s| {
            s.parse().map_err(|_| ConfigError::Address {
                key: "performers.source",
                value: s,
            })
        })
        .transpose()?;
    if let Some(a) = p.amount {
        check("performers.amount", (0.0..=1.0).contains(&a), a, "0..=1")?;
    }
    let name_ok = !p.name.is_empty() && p.name.len() <= protocol::MAX_STREAM_NAME_BYTES;
    check(
        "performers.name",
        name_ok,
        format!("{:?}", p.name),
        "1 to 64 bytes",
    )?;
    Ok(PerformerConfig {
        name: p.name,
        model: p.model,
        source,
        layout: p.layout,
        markerset: p.markerset,
        target: p.emotion,
        amount: p.amount,
    })
}

/// Parses `HOST:PORT[:profile]` (IPv6 as `[::1]:PORT[:profile]`); compact by default.
///
/// # Errors
/// [`ConfigError::Address`] or [`ConfigError::Profile`].
pub fn parse_send(text: &str) -> Result<(SocketAddr, Profile), ConfigError> {
    if let Ok(addr) = text.parse::<SocketAddr>() {
        return Ok((addr, Profile::Compact));
    }
    let (head, profile) = text.rsplit_once(':').ok_or_else(|| ConfigError::Address {
        key: "send",
        value: text.to_string(),
    })?;
    let addr = head.parse().map_err(|_| ConfigError::Address {
        key: "send",
        value: text.to_string(),
    })?;
    let profile = Profile::parse(profile).ok_or_else(|| ConfigError::Profile {
        value: text.to_string(),
    })?;
    Ok((addr, profile))
}

/// Token length bounds, bytes.
const TOKEN_BYTES: std::ops::RangeInclusive<usize> = 16..=256;

/// Checks a configured token: 16 to 256 URL-safe characters (letters, digits, `-._~`), so it
/// goes into `?token=` and a cookie as it is.
///
/// # Errors
/// [`ConfigError::Range`] naming `monitor_token`.
pub(crate) fn check_token(token: Option<String>) -> Result<Option<String>, ConfigError> {
    let Some(t) = token else { return Ok(None) };
    let safe = t
        .bytes()
        .all(|b| b.is_ascii_alphanumeric() || b"-._~".contains(&b));
    match safe && TOKEN_BYTES.contains(&t.len()) {
        true => Ok(Some(t)),
        false => Err(ConfigError::Range {
            key: "monitor_token",
            value: format!("of {} bytes", t.len()),
            range: "16 to 256 letters, digits or -._~",
        }),
    }
}
