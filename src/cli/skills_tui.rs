//! The terminal UI of `fitup skills run` (when standard output is a terminal):
//! running / finished / pending skills, part states, live joint values, the last
//! events; keys `p` pause, `r` resume, `a` abort, `m` a manual command, `q` quit
//! once the run ended. Drawn with crossterm on the alternate screen, raw mode.

use crate::kinematics::JointKind;
use crate::skills::{ControllerCommand, ManagerEvent, ManagerHandle, Plan};
use crossterm::event::{self, Event as TermEvent, KeyCode, KeyEventKind, KeyModifiers};
use crossterm::{cursor, execute, queue, style::Print, terminal};
use std::collections::{BTreeMap, VecDeque};
use std::io::Write;
use std::sync::mpsc::Receiver;
use std::time::Duration;

/// Longest manual command typed into the UI (bytes; further keys are ignored).
const MAX_INPUT: usize = 256;

/// What the manager's thread sends the UI.
pub(super) enum Msg {
    /// A manager event.
    Manager(ManagerEvent),
    /// The run ended: `None` when every skill finished, else the reason.
    End(Option<String>),
}

#[derive(Clone, Copy, PartialEq)]
enum Status {
    Pending,
    Running,
    Finished,
    Failed,
}

struct Ui<'a> {
    plan: &'a Plan,
    title: String,
    status: Vec<Status>,
    parts: BTreeMap<String, String>,
    log: VecDeque<String>,
    state: String,
    input: Option<String>,
    ended: bool,
}

impl Ui<'_> {
    fn note(&mut self, line: String) {
        self.log.push_back(line);
        while self.log.len() > 8 {
            self.log.pop_front();
        }
    }

    fn apply(&mut self, m: Msg) {
        match m {
            Msg::Manager(e) => {
                match &e {
                    ManagerEvent::Started(i, _) => self.set(*i, Status::Running),
                    ManagerEvent::Finished { skill, part, state } => {
                        self.set(*skill, Status::Finished);
                        self.parts.insert(part.clone(), state.name().to_string());
                    }
                    ManagerEvent::Failed(i, _) => self.set(*i, Status::Failed),
                    ManagerEvent::Paused => self.state = "paused".into(),
                    ManagerEvent::Resumed | ManagerEvent::Reconnected => {
                        self.state = "running".into()
                    }
                    ManagerEvent::Interrupted(..) => {
                        self.state = "interrupted, reconnecting".into()
                    }
                    _ => {}
                }
                self.note(e.describe());
            }
            Msg::End(reason) => {
                self.ended = true;
                self.state = match reason {
                    None => "done".into(),
                    Some(r) => format!("stopped: {r}"),
                };
            }
        }
    }

    fn set(&mut self, i: usize, s: Status) {
        if let Some(x) = self.status.get_mut(i) {
            *x = s;
        }
    }

    fn lines(&self, joints: &[f64], kinds: &[JointKind]) -> Vec<String> {
        let steps = &self.plan.steps;
        let of = |s: Status| -> Vec<&str> {
            steps
                .iter()
                .zip(&self.status)
                .filter(|(_, x)| **x == s)
                .map(|(p, _)| p.description.as_str())
                .collect()
        };
        let (running, finished, pending) = (
            of(Status::Running),
            of(Status::Finished),
            of(Status::Pending),
        );
        let mut out = vec![
            self.title.clone(),
            format!("state: {}", self.state),
            String::new(),
            format!("running:  {}", running.join(", ")),
            format!("finished ({}/{}):", finished.len(), steps.len()),
        ];
        let skip = finished.len().saturating_sub(4);
        out.extend(finished[skip..].iter().map(|d| format!("    {d}")));
        out.push(format!("pending ({}):", pending.len()));
        out.extend(pending.iter().take(4).map(|d| format!("    {d}")));
        let parts: Vec<String> = self.parts.iter().map(|(p, s)| format!("{p} {s}")).collect();
        out.push(format!("parts:    {}", parts.join(", ")));
        let j: Vec<String> = joints
            .iter()
            .zip(kinds)
            .map(|(v, k)| match k {
                JointKind::Prismatic => format!("{v:.1} mm"),
                _ => format!("{:.2}°", v.to_degrees()),
            })
            .collect();
        out.push(format!("joints:   {}", j.join("  ")));
        out.push(String::new());
        out.extend(self.log.iter().cloned());
        out.push(String::new());
        out.push(match &self.input {
            Some(t) => format!(
                "manual command (grasp MM, release MM, touch MM, output I 0|1; Enter, Esc): {t}"
            ),
            None if self.ended => "keys: q quit".into(),
            None => {
                "keys: p pause  r resume  a abort  m manual command  (q quits once the run ended)"
                    .into()
            }
        });
        out
    }
}

fn draw(out: &mut impl Write, lines: &[String]) -> std::io::Result<()> {
    let (width, height) = terminal::size().unwrap_or((100, 40));
    queue!(out, cursor::MoveTo(0, 0))?;
    for (row, l) in lines.iter().take(height as usize).enumerate() {
        // skill, part and robot names come from user files: escaped like every line
        let l = crate::diagnostics::printable(l, false);
        let cut: String = l.chars().take(width as usize).collect();
        queue!(
            out,
            cursor::MoveTo(0, row as u16),
            Print(cut),
            terminal::Clear(terminal::ClearType::UntilNewLine)
        )?;
    }
    queue!(out, terminal::Clear(terminal::ClearType::FromCursorDown))?;
    out.flush()
}

/// Runs the UI until the run ended and `q` was pressed. Ctrl-C aborts the run.
pub(super) fn run(
    plan: &Plan,
    title: String,
    handle: &ManagerHandle,
    messages: &Receiver<Msg>,
) -> std::io::Result<()> {
    let mut ui = Ui {
        plan,
        title,
        status: vec![Status::Pending; plan.steps.len()],
        parts: plan
            .steps
            .iter()
            .map(|s| (s.part.clone(), "-".to_string()))
            .collect(),
        log: VecDeque::new(),
        state: "connecting".into(),
        input: None,
        ended: false,
    };
    let kinds = plan.kinds();
    let mut out = std::io::stdout();
    terminal::enable_raw_mode()?;
    execute!(out, terminal::EnterAlternateScreen, cursor::Hide)?;
    let result = (|| -> std::io::Result<()> {
        loop {
            while let Ok(m) = messages.try_recv() {
                if ui.state == "connecting" {
                    ui.state = "running".into();
                }
                ui.apply(m);
            }
            draw(&mut out, &ui.lines(&handle.joints(), &kinds))?;
            if !event::poll(Duration::from_millis(100))? {
                continue;
            }
            let TermEvent::Key(k) = event::read()? else {
                continue;
            };
            if k.kind != KeyEventKind::Press {
                continue;
            }
            if k.code == KeyCode::Char('c') && k.modifiers.contains(KeyModifiers::CONTROL) {
                handle.abort();
                if ui.ended {
                    return Ok(());
                }
                continue;
            }
            if let Some(text) = ui.input.as_mut() {
                match k.code {
                    // The command line is capped like standard input's lines.
                    KeyCode::Char(c) if text.len() + c.len_utf8() <= MAX_INPUT => text.push(c),
                    KeyCode::Char(_) => {}
                    KeyCode::Backspace => {
                        text.pop();
                    }
                    KeyCode::Esc => ui.input = None,
                    KeyCode::Enter => {
                        let t = ui.input.take().unwrap_or_default();
                        match ControllerCommand::parse_manual(t.trim()) {
                            Some(c) => {
                                handle.manual(c);
                                ui.note(format!("queued manual {}", t.trim()));
                            }
                            None => ui.note(format!("unknown command `{}`", t.trim())),
                        }
                    }
                    _ => {}
                }
                continue;
            }
            match k.code {
                KeyCode::Char('p') => handle.pause(),
                KeyCode::Char('r') => handle.resume(),
                KeyCode::Char('a') => handle.abort(),
                KeyCode::Char('m') => ui.input = Some(String::new()),
                KeyCode::Char('q') if ui.ended => return Ok(()),
                KeyCode::Char('q') => {
                    ui.note("the run is going on: a aborts it, then q quits".into())
                }
                _ => {}
            }
        }
    })();
    let _ = execute!(out, cursor::Show, terminal::LeaveAlternateScreen);
    let _ = terminal::disable_raw_mode();
    result
}
