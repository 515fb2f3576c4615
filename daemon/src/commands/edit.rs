//! `emoshift edit`: component-space edits of a take ([`crate::offline::edit`]), streamed from
//! file to output in blocks ([`crate::offline::edit::edit_file`]) except Copy & Replace and
//! Copy & Add, which align another take to the whole of this one and hold both in memory.

use anyhow::{Context, Result};

use crate::cli::EditArgs;
use crate::exit::UsageError;
use crate::offline;
use crate::offline::edit::{edit_take, BadRequest, EditRequest};

pub(crate) fn run(args: &EditArgs) -> Result<()> {
    let add_from = match (&args.add_emotion_from, &args.other_model) {
        (Some(take), Some(model)) => Some((take.clone(), model.clone())),
        (Some(_), None) => {
            return Err(UsageError("--add-emotion-from needs --other-model m2.json".into()).into())
        }
        _ => None,
    };
    let request = EditRequest {
        translate: args.translate.iter().map(|kv| (kv.key, kv.value)).collect(),
        gain: args.gain.iter().map(|kv| (kv.key, kv.value)).collect(),
        to_emotion: args.to_emotion.clone(),
        amount: args.amount,
        lowpass_s: args.lowpass,
        replace_from: args.replace_emotion_from.clone(),
        add_from,
        keep_gaps: args.keep_gaps,
        start: args.range.start,
        end: args.range.end,
    };
    let mut inputs = vec![args.file.as_path(), args.model.as_path()];
    inputs.extend(args.replace_emotion_from.as_deref());
    inputs.extend(args.add_emotion_from.as_deref());
    inputs.extend(args.other_model.as_deref());
    offline::output::check_out(&args.out, &inputs, args.force)?;
    let model = offline::load_model(&args.model)?;
    let (frames, notices) = if request.replace_from.is_some() || request.add_from.is_some() {
        let take = offline::load_take(&args.file)?;
        let map = offline::match_take(&model, &take, &args.file)?;
        let notices = offline::take_notices(&model, (&take.labels, take.rate_hz), &map);
        let mut out = edit_take(&model, &args.model, &take, &args.file, &request).map_err(usage)?;
        if args.range.is_some() {
            let range = offline::trim::frame_range(&out, request.start, request.end)
                .with_context(|| format!("{}", args.file.display()))?;
            out.keep_frames(range);
        }
        replay::save(&args.out, &out).with_context(|| format!("{}", args.out.display()))?;
        (out.n_frames(), notices)
    } else {
        let mut progress = super::progress::for_stderr("edit");
        let done = offline::edit::edit_file(
            (&args.model, &model),
            (&args.file, offline::takes::input_limit()),
            &request,
            &args.out,
            (args.block_frames, args.keep_mb.saturating_mul(1 << 20)),
            progress.as_mut(),
        );
        let s = super::progress::settle(progress.as_mut(), done).map_err(usage)?;
        (s.frames, s.notices)
    };
    let unread = offline::takes::analog_left_out(&args.file);
    for notice in notices.iter().chain(&unread) {
        crate::out!("warning: {} {notice}", args.file.display());
    }
    crate::out!("edited {frames} frames -> {}", args.out.display());
    Ok(())
}

/// A [`BadRequest`] is the user's mistake: a usage error.
fn usage(e: anyhow::Error) -> anyhow::Error {
    match e.downcast::<BadRequest>() {
        Ok(bad) => UsageError(bad.0).into(),
        Err(e) => e,
    }
}
