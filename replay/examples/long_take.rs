//! A long take for measuring `project` and `edit` at scale (issue 18): the takes of a synthetic
//! session (`emoshift synth`) one after another, over and over, until the take lasts the
//! minutes asked, written in blocks so memory stays small whatever the length.
//!
//! Usage: `cargo run --release -p replay --example long_take -- SESSION_DIR MINUTES OUT`
//! (OUT's extension picks the format).

use std::path::{Path, PathBuf};

use replay::blocks::open_blocks;
use replay::TakeWriter;

const BLOCK_FRAMES: usize = 4096;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [dir, minutes, out] = args.as_slice() else {
        return Err("usage: long_take SESSION_DIR MINUTES OUT".into());
    };
    let mut takes: Vec<PathBuf> = std::fs::read_dir(dir)?
        .filter_map(|e| Some(e.ok()?.path()))
        .filter(|p| replay::Format::from_path(p).is_some())
        .collect();
    takes.sort();
    let first = takes.first().ok_or("no takes in the session folder")?;
    let header = open_blocks(first, u64::MAX)?.header().clone();
    let rate = header.rate_hz.ok_or("the first take has no rate")?;
    let frames = (minutes.parse::<f64>()? * 60.0 * rate).round() as usize;
    let mut writer = TakeWriter::create(Path::new(out), &header.labels, (rate, 1), Some(frames))?;
    let mut block = header.empty_take();
    'fill: for path in takes.iter().cycle() {
        let mut reader = open_blocks(path, u64::MAX)?;
        if reader.header().labels != header.labels {
            return Err(format!("{} has other markers", path.display()).into());
        }
        loop {
            let want = BLOCK_FRAMES.min(frames - writer.frames());
            if want == 0 {
                break 'fill;
            }
            if reader.read_block(want, &mut block)? == 0 {
                break;
            }
            writer.write_block(&block)?;
        }
    }
    writer.finish()?;
    println!("{out}: {frames} frames ({minutes} min at {rate} Hz)");
    Ok(())
}
