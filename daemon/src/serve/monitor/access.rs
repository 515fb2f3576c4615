//! Who may see the monitor page. Pure decisions over the request's Host, Origin, query and
//! cookie, tested without a server.
//!
//! - Bound to this host only (127.0.0.1 or ::1) without a configured token: no token, but the
//!   Host header must name loopback (`localhost`, `127.x.y.z`, `[::1]`), so a web page that
//!   rebinds its own name to 127.0.0.1 (DNS rebinding) is still refused.
//! - Bound anywhere else (other 127.x addresses count as elsewhere, so tests can stand in for
//!   another host), or with `monitor_token` set: a token. It comes once as `?token=`, is then
//!   kept in an HttpOnly, SameSite=Strict cookie (and dropped from the address bar by a
//!   redirect); without it every path answers a login prompt and nothing else.
//! - The WebSocket also checks its Origin: exactly `http://<Host>`, so another site's page in
//!   the operator's browser cannot drive the daemon.

use std::net::{IpAddr, Ipv4Addr, Ipv6Addr, SocketAddr};

/// The cookie that carries the token after the first visit, suffixed with the page's port.
///
/// Browsers keep cookies per host, not per port: serve's monitor and a session's performer
/// page on one stage PC would otherwise log each other out.
pub(crate) const COOKIE: &str = "emoshift_monitor";

/// The access rules of one monitor.
#[derive(Debug, Clone)]
pub(crate) struct Access {
    token: Option<String>,
    /// [`COOKIE`]`_<port>`.
    cookie: String,
}

/// What to do with a request.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum Verdict {
    /// Serve it.
    Allow,
    /// The query carried the right token: set the cookie and send the page again without it.
    SetCookie,
    /// Answer the login prompt (401); `wrong`: a token was given and is not this one.
    Login {
        /// A token was given and did not match.
        wrong: bool,
    },
    /// A Host header that does not name this host (403).
    BadHost,
}

impl Access {
    /// The rules for a page bound at `bound`: `token` as configured, or a fresh random one when
    /// the page is bound beyond this host and none is configured.
    pub(crate) fn new(bound: SocketAddr, token: Option<String>) -> Access {
        let this_host = matches!(bound.ip(), IpAddr::V4(v4) if v4 == Ipv4Addr::LOCALHOST)
            || matches!(bound.ip(), IpAddr::V6(v6) if v6 == Ipv6Addr::LOCALHOST);
        let token = match (token, this_host) {
            (Some(t), _) => Some(t),
            (None, true) => None,
            (None, false) => Some(random_token()),
        };
        let cookie = format!("{COOKIE}_{}", bound.port());
        Access { token, cookie }
    }

    /// The token pages need, if any.
    pub(crate) fn token(&self) -> Option<&str> {
        self.token.as_deref()
    }

    /// The verdict on a request with these headers and query.
    pub(crate) fn check(
        &self,
        host: Option<&str>,
        query: Option<&str>,
        cookie: Option<&str>,
    ) -> Verdict {
        let Some(token) = &self.token else {
            return match host.is_some_and(names_loopback) {
                true => Verdict::Allow,
                false => Verdict::BadHost,
            };
        };
        let given = query.and_then(|q| param(q, "token"));
        if given.is_some_and(|g| same(g, token)) {
            return Verdict::SetCookie;
        }
        if cookie
            .and_then(|c| cookie_value(c, &self.cookie))
            .is_some_and(|c| same(c, token))
        {
            return Verdict::Allow;
        }
        Verdict::Login {
            wrong: given.is_some(),
        }
    }

    /// Whether a WebSocket's Origin is this page's own: `http://<Host>`, Host valid.
    pub(crate) fn origin_ok(&self, host: Option<&str>, origin: Option<&str>) -> bool {
        let (Some(host), Some(origin)) = (host, origin) else {
            return false;
        };
        let host_ok = self.token.is_some() || names_loopback(host);
        host_ok && origin.strip_prefix("http://") == Some(host)
    }

    /// The `Set-Cookie` value that keeps the token.
    pub(crate) fn set_cookie(&self) -> Option<String> {
        self.token
            .as_ref()
            .map(|t| format!("{}={t}; Path=/; HttpOnly; SameSite=Strict", self.cookie))
    }
}

/// 128 random bits from the thread's CSPRNG, as 32 hex digits.
fn random_token() -> String {
    let bytes: [u8; 16] = rand::random();
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

/// Compares in time independent of where the texts differ.
fn same(a: &str, b: &str) -> bool {
    a.len() == b.len() && a.bytes().zip(b.bytes()).fold(0u8, |d, (x, y)| d | (x ^ y)) == 0
}

/// The value of `name` in a query `a=1&b=2` (tokens are URL-safe: no decoding).
fn param<'a>(query: &'a str, name: &str) -> Option<&'a str> {
    query
        .split('&')
        .filter_map(|kv| kv.split_once('='))
        .find(|(k, _)| *k == name)
        .map(|(_, v)| v)
}

/// The value of cookie `name` in a `Cookie:` header.
fn cookie_value<'a>(header: &'a str, name: &str) -> Option<&'a str> {
    header
        .split(';')
        .filter_map(|kv| kv.trim().split_once('='))
        .find(|(k, _)| *k == name)
        .map(|(_, v)| v)
}

/// Whether a Host header names this host by a loopback name or address.
fn names_loopback(host: &str) -> bool {
    let name = match host.strip_prefix('[') {
        Some(v6) => v6.split(']').next().unwrap_or(""),
        None => host.rsplit_once(':').map_or(host, |(h, _)| h),
    };
    name.eq_ignore_ascii_case("localhost")
        || name.parse::<IpAddr>().is_ok_and(|ip| ip.is_loopback())
}

#[cfg(test)]
mod tests;
