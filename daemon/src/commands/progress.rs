//! Drawing [`Progress`]: a bar on a terminal (indicatif), and in a pipe or a log a line on
//! stderr every [`LINE_INTERVAL`] while a step runs (done, total, rate, ETA) and one when it
//! ends, so a job run under `nohup` or CI shows where it is. Work shorter than the interval
//! prints nothing (a failure stays the one line on stderr), and neither does an abandoned step.
//! `EMOSHIFT_PROGRESS_SECS` sets the interval (0: every step and advance).

use std::io::{IsTerminal, Write};
use std::time::{Duration, Instant};

use indicatif::{HumanCount, ProgressBar, ProgressState, ProgressStyle};

use crate::offline::progress::Progress;

/// Time between two progress lines when stderr is not a terminal.
pub const LINE_INTERVAL: Duration = Duration::from_secs(5);

/// The progress display of a command: a bar on a terminal, lines otherwise.
pub fn for_stderr(command: &'static str) -> Box<dyn Progress + Send> {
    if std::io::stderr().is_terminal() {
        return Box::new(Bar::new(command));
    }
    let interval = std::env::var("EMOSHIFT_PROGRESS_SECS")
        .ok()
        .and_then(|v| v.parse::<f64>().ok())
        .filter(|v| v.is_finite() && *v >= 0.0)
        .map_or(LINE_INTERVAL, Duration::from_secs_f64);
    // Line-buffered: stderr is not, and a line's formatting writes it piece by piece.
    Box::new(Lines::new(
        command,
        std::io::LineWriter::new(std::io::stderr()),
        interval,
    ))
}

/// Ends the display of work that returned `result`: cleared when it succeeded, stopped
/// without a final "done" line when it failed (the error is the one line that matters).
///
/// # Errors
/// `result`'s error.
pub fn settle<T>(progress: &mut dyn Progress, result: anyhow::Result<T>) -> anyhow::Result<T> {
    match &result {
        Ok(_) => progress.finish(),
        Err(_) => progress.abandon(),
    }
    result
}

/// An indicatif bar per step (a spinner when the total is unknown).
#[derive(Debug)]
struct Bar {
    command: &'static str,
    bar: Option<ProgressBar>,
}

impl Bar {
    fn new(command: &'static str) -> Self {
        Self { command, bar: None }
    }
}

impl Progress for Bar {
    fn step(&mut self, name: &str, unit: &'static str, total: Option<u64>) {
        if let Some(bar) = self.bar.take() {
            bar.finish_and_clear();
        }
        let template = match total {
            Some(_) => format!(
                "{{prefix}} {{wide_bar}} {{human_pos}}/{{human_len}} {unit} {{rate}} ETA {{eta}} {{msg}}"
            ),
            None => format!("{{prefix}} {{spinner}} {{human_pos}} {unit} {{rate}} {{msg}}"),
        };
        let style = ProgressStyle::with_template(&template)
            .expect("the templates above are valid")
            .with_key(
                "rate",
                |state: &ProgressState, w: &mut dyn std::fmt::Write| {
                    // Whole units per second: indicatif's own key prints four decimals.
                    let _ = write!(w, "{}/s", HumanCount(state.per_sec() as u64));
                },
            )
            .progress_chars("=> ");
        let bar = match total {
            Some(n) => ProgressBar::new(n),
            None => ProgressBar::new_spinner(),
        };
        bar.set_style(style);
        bar.set_prefix(format!("{}: {name}", self.command));
        bar.enable_steady_tick(Duration::from_millis(200));
        self.bar = Some(bar);
    }

    fn advance(&mut self, n: u64) {
        if let Some(bar) = &self.bar {
            bar.inc(n);
        }
    }

    fn note(&mut self, text: &str) {
        if let Some(bar) = &self.bar {
            bar.set_message(text.to_string());
        }
    }

    fn finish(&mut self) {
        if let Some(bar) = self.bar.take() {
            bar.finish_and_clear();
        }
    }

    fn abandon(&mut self) {
        self.finish();
    }
}

/// Plain lines: a step's state every `interval`, and its end.
#[derive(Debug)]
pub struct Lines<W: Write> {
    command: &'static str,
    out: W,
    interval: Duration,
    /// Nothing is printed before this: short work stays quiet.
    quiet_until: Instant,
    step: Option<Step>,
    note: String,
}

#[derive(Debug)]
struct Step {
    name: String,
    unit: &'static str,
    total: Option<u64>,
    done: u64,
    started: Instant,
    last_line: Instant,
}

/// A step's time: to the hundredth of a second under ten seconds, where steps differ.
fn seconds(secs: f64) -> String {
    // Milliseconds under a second: a short train's steps (the head decision of a 12,000-frame
    // session, some tens of milliseconds) are compared as shares of the whole.
    if secs < 1.0 {
        format!("{secs:.3}")
    } else if secs < 10.0 {
        format!("{secs:.2}")
    } else {
        format!("{secs:.1}")
    }
}

impl<W: Write> Lines<W> {
    /// Lines for `command` into `out`, one every `interval` while a step runs.
    pub fn new(command: &'static str, out: W, interval: Duration) -> Self {
        Self {
            command,
            out,
            interval,
            quiet_until: Instant::now() + interval,
            step: None,
            note: String::new(),
        }
    }

    /// The writer (tests read what was written).
    pub fn into_inner(self) -> W {
        self.out
    }

    fn end_step(&mut self) {
        let Some(s) = self.step.take() else {
            return;
        };
        if Instant::now() < self.quiet_until {
            return;
        }
        let secs = s.started.elapsed().as_secs_f64();
        let rate = s.done as f64 / secs.max(1e-9);
        // Progress lines are best effort: a closed stderr must not fail the work.
        if s.done == 0 && s.total.is_none() {
            // A step that counts nothing (restarts in memory): its time is what there is.
            let _ = writeln!(
                self.out,
                "{}: {} done in {} s{}",
                self.command,
                s.name,
                seconds(secs),
                note(&self.note)
            );
            return;
        }
        let _ = writeln!(
            self.out,
            "{}: {} done: {} {} in {} s ({} {}/s){}",
            self.command,
            s.name,
            HumanCount(s.done),
            s.unit,
            seconds(secs),
            HumanCount(rate as u64),
            s.unit,
            note(&self.note)
        );
    }

    fn line(&mut self) {
        let Some(s) = &self.step else {
            return;
        };
        let secs = s.started.elapsed().as_secs_f64();
        let rate = s.done as f64 / secs.max(1e-9);
        let of = match s.total {
            Some(t) => {
                let eta = if rate > 0.0 {
                    format!(", ETA {:.0} s", t.saturating_sub(s.done) as f64 / rate)
                } else {
                    String::new()
                };
                format!(
                    " / {} {} ({:.0} %){eta}",
                    HumanCount(t),
                    s.unit,
                    100.0 * s.done as f64 / t.max(1) as f64
                )
            }
            None => format!(" {}", s.unit),
        };
        let _ = writeln!(
            self.out,
            "{}: {}: {}{of}, {} {}/s{}",
            self.command,
            s.name,
            HumanCount(s.done),
            HumanCount(rate as u64),
            s.unit,
            note(&self.note)
        );
    }
}

fn note(text: &str) -> String {
    if text.is_empty() {
        String::new()
    } else {
        format!(" [{text}]")
    }
}

impl<W: Write + Send> Progress for Lines<W> {
    fn step(&mut self, name: &str, unit: &'static str, total: Option<u64>) {
        self.end_step();
        self.note.clear();
        let now = Instant::now();
        self.step = Some(Step {
            name: name.to_string(),
            unit,
            total,
            done: 0,
            started: now,
            last_line: now,
        });
    }

    fn advance(&mut self, n: u64) {
        let Some(s) = &mut self.step else {
            return;
        };
        s.done += n;
        if s.last_line.elapsed() >= self.interval && Instant::now() >= self.quiet_until {
            s.last_line = Instant::now();
            self.line();
        }
    }

    fn note(&mut self, text: &str) {
        self.note.clear();
        self.note.push_str(text);
    }

    fn finish(&mut self) {
        self.end_step();
    }

    fn abandon(&mut self) {
        self.step = None;
    }
}

#[cfg(test)]
mod tests;
