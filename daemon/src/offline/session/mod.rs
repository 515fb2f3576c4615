//! A calibration session (`emoshift session`) without its I/O: the [`script`], the checks a
//! take passes ([`check`]), and [`Sitting`], the state machine of the takes: which one is
//! prompted, which were accepted, what each control does.
//!
//! Call order: [`Sitting::handle`] for each control; when it answers [`Step::Record`] the
//! caller records, and on [`Step::Stop`] it stops, checks the take and reports the outcome
//! with [`Sitting::handle_checked`]. [`Sitting::manifest`] is the `session.toml` of what was
//! accepted, written after every accepted take.

pub mod advice;
pub mod check;
pub mod script;

use protocol::{SessionControl, SessionStatus};
use replay::session::{Session, SessionTake};

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
    /// The prompt moved (skip, back): show it.
    Moved,
}

/// The session's takes and where the operator is.
#[derive(Debug, Clone)]
pub struct Sitting {
    script: Script,
    plan: Vec<Prompt>,
    accepted: Vec<bool>,
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
            s.accepted[i] = manifest.takes.iter().any(|t| t.file == file);
        }
        s.rate_hz = Some(manifest.rate_hz);
        s.last_accepted = (0..s.plan.len()).rev().find(|&i| s.accepted[i]);
        s.move_on();
        s
    }

    /// Offers the takes named (`s03_happy.c3d` or `s03_happy`) again: each stays on disk and
    /// in the manifest's folder until its new take is accepted, and then moves to
    /// `replaced/`.
    ///
    /// # Errors
    /// A name that is no take of the script.
    pub fn redo(&mut self, names: &[String]) -> Result<(), String> {
        for name in names {
            let file = match name.ends_with(&format!(".{}", self.ext)) {
                true => name.clone(),
                false => format!("{name}.{}", self.ext),
            };
            let Some(i) = self
                .plan
                .iter()
                .position(|p| p.file_name(&self.ext) == file)
            else {
                return Err(format!("--redo {name}: no such take in the script"));
            };
            self.accepted[i] = false;
        }
        self.cursor = 0;
        self.state = State::Waiting;
        self.move_on();
        Ok(())
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
            C::Finish => Ok(Step::Finish),
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
                self.last_accepted = Some(self.cursor);
                self.rate_hz.get_or_insert(rate_hz);
                self.state = State::Waiting;
                self.move_on();
            }
            Err(why) => self.state = State::Review(why),
        }
    }

    /// From the cursor on, the first take not accepted (wrapping round); done when none.
    fn move_on(&mut self) {
        let n = self.plan.len();
        match (0..n)
            .map(|k| (self.cursor + k) % n)
            .find(|&i| !self.accepted[i])
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
            .filter(|(_, &a)| a)
            .map(|(p, _)| SessionTake {
                file: p.file_name(&self.ext),
                sentence: p.sentence_id(),
                emotion: p.emotion.clone(),
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
