//! `emoshift repair FILE [--out F]`: a take cut off by a crash made whole (see
//! [`replay::repair`]).

use anyhow::{Context, Result};

use crate::cli::RepairArgs;

pub(crate) fn run(args: &RepairArgs) -> Result<()> {
    if let Some(out) = &args.out {
        crate::offline::output::check_out(out, &[&args.file], args.force)?;
        if replay::Format::from_path(out) != replay::Format::from_path(&args.file) {
            return Err(crate::exit::UsageError(format!(
                "--out {} must have the extension of {}: repair keeps the format (convert it \
                 after with `emoshift convert`)",
                out.display(),
                args.file.display()
            ))
            .into());
        }
    }
    let file = args.file.display();
    let done = replay::repair::repair(&args.file, args.out.as_deref())
        .with_context(|| format!("{file}: not repaired"))?;
    let before = &done.before;
    let Some(written) = &done.written else {
        crate::out!(
            "{file}: nothing to repair: its header and data agree ({} frames)",
            done.frames
        );
        return Ok(());
    };
    let said = match before.header_frames {
        Some(h) if h != done.frames => format!(" (its header said {h})"),
        _ => String::new(),
    };
    let torn = if before.torn_bytes > 0 {
        format!(
            "; {} bytes of a last frame cut off mid-write dropped",
            before.torn_bytes
        )
    } else {
        String::new()
    };
    crate::out!(
        "repaired {}: {} frames{said}{torn}",
        written.display(),
        done.frames
    );
    Ok(())
}
