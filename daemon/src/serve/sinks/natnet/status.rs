//! The NatNet server's counters and its `/status` pairs (`natnet_server/...`): the clients with
//! their bitstreams and leases, frames and bytes sent, every refusal counted.

use std::time::Instant;

use protocol::StatusValue;

use super::session::Session;

/// `/status` pairs: `natnet_server/...`.
pub fn status_pairs(s: &Session) -> Vec<(String, StatusValue)> {
    let multicast = s.multicast().map_or(String::new(), |(g, _)| g.to_string());
    let markersets: Vec<&str> = s.defs.markersets.iter().map(|m| m.name.as_str()).collect();
    let mut out = vec![
        text("multicast", multicast),
        int("clients", s.client_count() as u64),
        int("pending", s.pending() as u64),
        text("markersets", markersets.join(",")),
    ];
    out.extend(s.counters.pairs().into_iter().map(|(k, v)| int(k, v)));
    let now = Instant::now();
    for (n, client) in s.clients().enumerate() {
        let v = client.wants;
        let lease = client.lease_left(now).unwrap_or_default();
        out.push(text(&format!("client/{n}/addr"), client.addr.to_string()));
        out.push(text(
            &format!("client/{n}/version"),
            format!("{}.{}", v.major, v.minor),
        ));
        out.push(int(
            &format!("client/{n}/lease_ms"),
            lease.as_millis() as u64,
        ));
        out.push(int(&format!("client/{n}/frames"), client.sends));
    }
    out
}

fn int(k: &str, v: u64) -> (String, StatusValue) {
    (
        format!("natnet_server/{k}"),
        StatusValue::Int(i64::try_from(v).unwrap_or(i64::MAX)),
    )
}

fn text(k: &str, v: String) -> (String, StatusValue) {
    (format!("natnet_server/{k}"), StatusValue::Text(v))
}
