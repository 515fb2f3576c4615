//! A calibration session (`emoshift session`) without its I/O: the [`script`], the checks a
//! take passes ([`check`]), and [`Sitting`], the state machine of the takes: which one is
//! prompted, which were accepted, what each control does.
//!
//! Call order: [`Sitting::handle`] for each control; when it answers [`Step::Record`] the
//! caller records, and on [`Step::Stop`] it stops, checks the take and reports the outcome
//! with [`Sitting::handle_checked`]. [`Sitting::manifest`] is the `session.toml` of what was
//! accepted, written after every accepted take. On [`Step::Finish`] the caller trains and
//! analyses; when the analysis says what to redo it calls [`Sitting::offer`], and a
//! `/session/redo` then prompts just those takes again ([`Step::Moved`]), while a second
//! finish ends the session with the model as it is ([`Step::Close`]).

pub mod advice;
pub mod check;
pub mod script;

use protocol::{SessionControl, SessionStatus};
use replay::session::{Session, SessionTake, TakeRange};

use script::{Prompt, Script};

/// Where the prompted take is.
#[derive(Debug, Clone, PartialEq)]
pub enum State {
    /// Waiting for start.
    Waiting,
    /// Recording.
    Recording,
    /// Refused, and why: retake or skip.
    Review(String),
    /// Every take accepted: finish (or retake the last one).
    Done,
}

impl State {
    /// The wire name: `waiting`, `recording`, `review` or `done`.
    pub fn as_str(&self) -> &'static str {
        match self {
            State::Waiting => "waiting",
            State::Recording => "recording",
            State::Review(_) => "review",
            State::Done => "done",
        }
    }
}

/// What the caller does after a control.
#[derive(Debug, Clone, PartialEq)]
pub enum Step {
    /// Record the prompted take (the operator asked; it replaces an accepted one when
    /// `replaces`).
    Record {
        /// The prompt's take.
        prompt: Prompt,
        /// An accepted take of this prompt exists and is to be replaced once this one passes.
        replaces: bool,
    },
    /// Stop recording, check the take, then [`Sitting::handle_checked`].
    Stop,
    /// Answer with the status.
    Status,
    /// Train and analyse what was accepted.
    Finish,
    /// End the session with the model the last finish trained (its redo offer declined).
    Close,
    /// The prompt moved (skip, back): show it.
    Moved,
}

/// The session's takes and where the operator is.
#[derive(Debug, Clone)]
pub struct Sitting {
    script: Script,
    plan: Vec<Prompt>,
    accepted: Vec<bool>,
    /// The `start`/`end` of each accepted take, as a resumed manifest gave them (an edit the
    /// operator made by hand survives the manifest being written again; a new take is whole).
    ranges: Vec<TakeRange>,
    /// Accepted takes to record again: they stay in the manifest until their new take passes.
    redo: Vec<bool>,
    /// The takes the last finish said to redo, until `/session/redo` or another control.
    offered: Vec<usize>,
    cursor: usize,
    state: State,
    last_accepted: Option<usize>,
    rate_hz: Option<f64>,
    ext: String,
}

impl Sitting {
    /// A new session of `script`, takes written as `ext` (c3d, trc or csv).
    pub fn new(script: Script, ext: &str) -> Sitting {
        let plan = script.plan();
        Sitting {
            accepted: vec![false; plan.len()],
            ranges: vec![TakeRange::WHOLE; plan.len()],
            redo: vec![false; plan.len()],
            offered: Vec::new(),
            script,
            plan,
            cursor: 0,
            state: State::Waiting,
            last_accepted: None,
            rate_hz: None,
            ext: ext.to_string(),
        }
    }

    /// A session resumed: the takes `manifest` lists are accepted; the first other take is
    /// prompted.
    pub fn resume(script: Script, ext: &str, manifest: &Session) -> Sitting {
        let mut s = Sitting::new(script, ext);
        for (i, p) in s.plan.iter().enumerate() {
            let file = p.file_name(&s.ext);
            let listed = manifest.takes.iter().find(|t| t.file == file);
            s.accepted[i] = listed.is_some();
            s.ranges[i] = listed.map_or(TakeRange::WHOLE, SessionTake::range);
        }
        s.rate_hz = Some(manifest.rate_hz);
        s.last_accepted = (0..s.plan.len()).rev().find(|&i| s.accepted[i]);
        s.move_on();
        s
    }

    /// Offers the takes named (`s03_happy.c3d` or `s03_happy`) again (`--redo`): each stays
    /// on disk and in the manifest until its new take is accepted, and then moves to
    /// `replaced/`.
    ///
    /// # Errors
    /// A name that is no take of the script.
    pub fn redo(&mut self, names: &[String]) -> Result<(), String> {
        let takes = self.takes_named(names)?;
        self.redo_takes(&takes);
        Ok(())
    }

    /// What the finish just made said to redo (take files or names): `/session/redo` records
    /// them again, a second finish declines.
    ///
    /// # Errors
    /// A name that is no take of the script.
    pub fn offer(&mut self, names: &[String]) -> Result<(), String> {
        self.offered = self.takes_named(names)?;
        Ok(())
    }

    /// The take files offered for a redo (empty when none is).
    pub fn offered(&self) -> Vec<String> {
        self.offered
            .iter()
            .map(|&i| self.plan[i].file_name(&self.ext))
            .collect()
    }

    fn takes_named(&self, names: &[String]) -> Result<Vec<usize>, String> {
        let suffix = format!(".{}", self.ext);
        names
            .iter()
            .map(|name| {
                let file = match name.ends_with(&suffix) {
                    true => name.clone(),
                    false => format!("{name}{suffix}"),
                };
                self.plan
                    .iter()
                    .position(|p| p.file_name(&self.ext) == file)
                    .ok_or_else(|| format!("redo {name}: no such take in the script"))
            })
            .collect()
    }

    fn redo_takes(&mut self, takes: &[usize]) {
        for &i in takes {
            self.redo[i] = true;
        }
        self.cursor = takes.iter().copied().min().unwrap_or(0);
        self.state = State::Waiting;
        self.move_on();
    }

    /// The script.
    pub fn script(&self) -> &Script {
        &self.script
    }

    /// The state.
    pub fn state(&self) -> &State {
        &self.state
    }

    /// The prompted take (the last one when every take is done).
    pub fn prompt(&self) -> &Prompt {
        &self.plan[self.cursor.min(self.plan.len() - 1)]
    }

    /// The prompted take's index in the plan.
    pub fn cursor(&self) -> usize {
        self.cursor
    }

    /// Takes in the plan.
    pub fn takes(&self) -> usize {
        self.plan.len()
    }

    /// Takes accepted.
    pub fn accepted(&self) -> usize {
        self.accepted.iter().filter(|&&a| a).count()
    }

    /// Accepted takes waiting to be recorded again.
    pub fn to_redo(&self) -> usize {
        self.redo.iter().filter(|&&r| r).count()
    }

    /// The take files' extension.
    pub fn ext(&self) -> &str {
        &self.ext
    }

    /// The status `/session/status` answers.
    pub fn status(&self) -> SessionStatus {
        let p = self.prompt();
        let cursor = match self.state {
            State::Done => self.plan.len(),
            _ => self.cursor,
        };
        SessionStatus {
            take: cursor as i32,
            takes: self.plan.len() as i32,
            sentence: p.sentence as i32 + 1,
            emotion: p.emotion.clone(),
            state: self.state.as_str().to_string(),
            text: self.script.sentences[p.sentence].text.clone(),
        }
    }

    /// Applies a control.
    ///
    /// # Errors
    /// Why the control does nothing now, and what to send instead.
    pub fn handle(&mut self, control: SessionControl) -> Result<Step, String> {
        use SessionControl as C;
        let recording = self.state == State::Recording;
        if !matches!(control, C::Status | C::Finish | C::Redo) && !recording {
            // Doing anything else declines the offer: the next finish trains again.
            self.offered.clear();
        }
        match control {
            C::Status => Ok(Step::Status),
            C::Stop if recording => Ok(Step::Stop),
            C::Stop => Err("not recording: start first".into()),
            _ if recording => Err("recording: stop the take first".into()),
            C::Start if self.state == State::Done => {
                Err("every take is done: finish, or retake the last take".into())
            }
            C::Start => Ok(self.record()),
            C::Retake => {
                if matches!(self.state, State::Waiting | State::Done) {
                    let Some(last) = self.last_accepted else {
                        return Err("no take recorded yet: start".into());
                    };
                    self.cursor = last;
                }
                Ok(self.record())
            }
            C::Skip => {
                self.cursor = (self.cursor + 1) % self.plan.len();
                self.state = State::Waiting;
                self.move_on();
                Ok(Step::Moved)
            }
            C::Back => {
                self.cursor = self.cursor.saturating_sub(1);
                self.state = State::Waiting;
                Ok(Step::Moved)
            }
            C::Finish if self.accepted() == 0 => {
                Err("no take accepted yet: record the session first".into())
            }
            C::Finish if !self.offered.is_empty() => Ok(Step::Close),
            C::Finish => Ok(Step::Finish),
            C::Redo if self.offered.is_empty() => {
                Err("nothing offered to redo: finish first, it says what to redo".into())
            }
            C::Redo => {
                let offered = std::mem::take(&mut self.offered);
                self.redo_takes(&offered);
                Ok(Step::Moved)
            }
        }
    }

    fn record(&mut self) -> Step {
        self.state = State::Recording;
        Step::Record {
            prompt: self.prompt().clone(),
            replaces: self.accepted[self.cursor],
        }
    }

    /// The outcome of the take just stopped: `Ok` with its rate when it passed the checks and
    /// is in place, else why it was refused.
    pub fn handle_checked(&mut self, outcome: Result<f64, String>) {
        match outcome {
            Ok(rate_hz) => {
                self.accepted[self.cursor] = true;
                self.ranges[self.cursor] = TakeRange::WHOLE;
                self.redo[self.cursor] = false;
                self.last_accepted = Some(self.cursor);
                self.rate_hz.get_or_insert(rate_hz);
                self.state = State::Waiting;
                self.move_on();
            }
            Err(why) => self.state = State::Review(why),
        }
    }

    /// From the cursor on, the first take not accepted or to redo (wrapping round); done
    /// when none.
    fn move_on(&mut self) {
        let n = self.plan.len();
        match (0..n)
            .map(|k| (self.cursor + k) % n)
            .find(|&i| !self.accepted[i] || self.redo[i])
        {
            Some(i) => self.cursor = i,
            None => self.state = State::Done,
        }
    }

    /// The manifest of the accepted takes, in plan order (`None` before the first).
    pub fn manifest(&self) -> Option<Session> {
        let takes: Vec<SessionTake> = self
            .plan
            .iter()
            .zip(&self.accepted)
            .zip(&self.ranges)
            .filter(|((_, &a), _)| a)
            .map(|((p, _), range)| SessionTake {
                start: range.start,
                end: range.end,
                ..SessionTake::whole(p.file_name(&self.ext), p.sentence_id(), p.emotion.clone())
            })
            .collect();
        (!takes.is_empty()).then(|| Session {
            rate_hz: self.rate_hz.unwrap_or(120.0),
            takes,
            base_dir: Default::default(),
        })
    }

    /// The accepted take before the prompted one in plan order (for the copy check).
    pub fn previous_accepted(&self) -> Option<Prompt> {
        self.last_accepted.map(|i| self.plan[i].clone())
    }
}

#[cfg(test)]
mod tests;
