//! Proves `replay::decimal::push_f32` writes every `f32` as std's `Display` does: all 2^32 bit
//! patterns (12-15 minutes on one core of the team's loaded machine), or every STRIDE-th.
//!
//! Usage: `cargo run --release -p replay --example shortest_f32 -- [STRIDE]`

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let stride: u64 = match std::env::args().nth(1) {
        Some(s) => s.parse()?,
        None => 1,
    };
    let (mut ours, mut std) = (String::new(), String::new());
    let mut checked = 0u64;
    for bits in (0..=u64::from(u32::MAX)).step_by(stride.max(1) as usize) {
        let value = f32::from_bits(bits as u32);
        ours.clear();
        std.clear();
        replay::decimal::push_f32(&mut ours, value);
        std::fmt::Write::write_fmt(&mut std, format_args!("{value}"))?;
        if ours != std {
            return Err(format!("bits {bits:#010x}: ours {ours}, std {std}").into());
        }
        checked += 1;
    }
    println!("{checked} f32 values written as std writes them");
    Ok(())
}
