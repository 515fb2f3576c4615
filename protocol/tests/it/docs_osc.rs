//! docs/osc.md is the one OSC address table: every address `protocol::address` defines is in it.

/// The string constants `protocol/src/address.rs` defines, as (name, value).
fn defined_addresses() -> Vec<(String, String)> {
    let source = include_str!("../../src/address.rs");
    source
        .lines()
        .filter_map(|line| {
            let rest = line.trim().strip_prefix("pub const ")?;
            let (name, value) = rest.split_once(": &str = \"")?;
            let value = value.strip_suffix("\";")?;
            Some((name.to_string(), value.to_string()))
        })
        .collect()
}

#[test]
fn every_address_in_protocol_is_in_docs_osc_md() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../docs/osc.md");
    let table = std::fs::read_to_string(path).expect("docs/osc.md is in the workspace");
    let addresses = defined_addresses();
    assert!(
        addresses.len() >= 25,
        "address.rs's constants were not found: {addresses:?}"
    );
    let missing: Vec<&(String, String)> = addresses
        .iter()
        .filter(|(name, value)| {
            // An address in code font; a suffix (`/confirm`) at the end of one.
            let in_code = if name.ends_with("_SUFFIX") {
                format!("{value}`")
            } else {
                format!("`{value}`")
            };
            !table.contains(&in_code)
        })
        .collect();
    assert!(
        missing.is_empty(),
        "addresses in protocol/src/address.rs missing from docs/osc.md: {missing:?}"
    );
}
