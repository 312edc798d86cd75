//! How keys and job reports change the state: [`App::update`].
//!
//! Keys (also in the help screen, `render/help.rs`):
//! - everywhere: `q` or Ctrl-C quit, `?` help, Tab / Shift-Tab next / previous
//!   pane, `1` `2` `3` the panes, `/` jump to a joint (`/5`) or a zone
//!   (`/5 3`, `/5.3`);
//! - overview: arrows or hjkl move (up is up the dam), Enter opens the zone;
//! - flagged list: ↑↓ or jk, Enter opens the zone;
//! - zone: arrows or hjkl go to the neighbouring zone, `w` opens the what-if,
//!   Esc goes back;
//! - what-if: ↑↓ or jk choose the field, ←→ hl - + change it (→ more
//!   supercooling, a later date), PgDn a week later and PgUp a week earlier
//!   on the date, Enter re-simulates, `c` cancels, `s` saves the schedules,
//!   Esc cancels a running job or closes the form.

use chrono::Duration;
use ratatui::crossterm::event::{KeyCode, KeyEvent, KeyEventKind, KeyModifiers};

use super::app::{App, Field, Pane, Prompt, Running, WhatIfForm, ZoneView};
use super::event::{Command, Event, JobEvent};
use crate::planner::whatif::WhatIf;
use crate::vocab::ZoneId;

impl App {
    /// Applies one event; returns the work the runtime must start.
    pub fn update(&mut self, event: Event) -> Vec<Command> {
        match event {
            Event::Key(k) if k.kind != KeyEventKind::Release => self.on_key(k),
            Event::Key(_) | Event::Resize => Vec::new(),
            Event::Job(j) => {
                self.on_job(j);
                Vec::new()
            }
        }
    }

    fn on_key(&mut self, k: KeyEvent) -> Vec<Command> {
        let ctrl_c = k.code == KeyCode::Char('c') && k.modifiers.contains(KeyModifiers::CONTROL);
        if ctrl_c {
            return self.quit();
        }
        if self.prompt.is_some() {
            return self.on_prompt_key(k);
        }
        if self.help {
            match k.code {
                KeyCode::Char('q') => return self.quit(),
                KeyCode::Esc | KeyCode::Char('?') | KeyCode::Enter => self.help = false,
                _ => {}
            }
            return Vec::new();
        }
        if self.data.is_none() {
            // Planning: only quit and help.
            match k.code {
                KeyCode::Char('q') | KeyCode::Esc => return self.quit(),
                KeyCode::Char('?') => self.help = true,
                _ => {}
            }
            return Vec::new();
        }
        if self.form_open() {
            if let Some(cmds) = self.on_form_key(k) {
                return cmds;
            }
        }
        match k.code {
            KeyCode::Char('q') => return self.quit(),
            KeyCode::Char('?') => self.help = true,
            KeyCode::Char('/') => self.prompt = Some(Prompt::default()),
            KeyCode::Tab => self.cycle_pane(1),
            KeyCode::BackTab => self.cycle_pane(-1),
            KeyCode::Char('1') => self.pane = Pane::Overview,
            KeyCode::Char('2') => self.pane = Pane::Flagged,
            KeyCode::Char('3') if self.zone.is_some() => self.pane = Pane::Zone,
            _ => {
                return match self.pane {
                    Pane::Overview => self.on_overview_key(k),
                    Pane::Flagged => self.on_flagged_key(k),
                    Pane::Zone => self.on_zone_key(k),
                }
            }
        }
        Vec::new()
    }

    fn quit(&mut self) -> Vec<Command> {
        self.quit = true;
        if self.running().is_some() {
            vec![Command::CancelWhatIf]
        } else {
            Vec::new()
        }
    }

    fn cycle_pane(&mut self, step: i32) {
        let panes: Vec<Pane> = Pane::ALL
            .into_iter()
            .filter(|p| *p != Pane::Zone || self.zone.is_some())
            .collect();
        let i = panes.iter().position(|p| *p == self.pane).unwrap_or(0) as i32;
        let n = panes.len() as i32;
        self.pane = panes[((i + step).rem_euclid(n)) as usize];
    }

    fn on_overview_key(&mut self, k: KeyEvent) -> Vec<Command> {
        let Some(data) = self.data.clone() else {
            return Vec::new();
        };
        let (cols, rows) = (data.grid.joints.len(), data.grid.zones.len());
        let (c, r) = &mut self.cursor;
        match k.code {
            KeyCode::Left | KeyCode::Char('h') => *c = c.saturating_sub(1),
            KeyCode::Right | KeyCode::Char('l') => *c = (*c + 1).min(cols.saturating_sub(1)),
            KeyCode::Up | KeyCode::Char('k') => *r = (*r + 1).min(rows.saturating_sub(1)),
            KeyCode::Down | KeyCode::Char('j') => *r = r.saturating_sub(1),
            KeyCode::Enter => {
                let (c, r) = self.cursor;
                if let Some(cell) = data.grid.cell(c, r) {
                    return self.open_zone(cell.joint, cell.zone);
                }
                self.status = Some("no grouting zone there".into());
            }
            _ => {}
        }
        Vec::new()
    }

    fn on_flagged_key(&mut self, k: KeyEvent) -> Vec<Command> {
        let n = self.flagged().len();
        match k.code {
            KeyCode::Up | KeyCode::Char('k') => {
                self.flagged_row = self.flagged_row.saturating_sub(1)
            }
            KeyCode::Down | KeyCode::Char('j') => {
                self.flagged_row = (self.flagged_row + 1).min(n.saturating_sub(1))
            }
            KeyCode::Home | KeyCode::Char('g') => self.flagged_row = 0,
            KeyCode::End | KeyCode::Char('G') => self.flagged_row = n.saturating_sub(1),
            KeyCode::Enter => {
                let key = self
                    .flagged()
                    .get(self.flagged_row)
                    .map(|z| (z.joint, z.zone));
                if let Some((j, z)) = key {
                    return self.open_zone(j, z);
                }
            }
            _ => {}
        }
        Vec::new()
    }

    fn on_zone_key(&mut self, k: KeyEvent) -> Vec<Command> {
        let Some(view) = &self.zone else {
            return Vec::new();
        };
        let (j, z) = (view.joint, view.zone);
        let step = match k.code {
            KeyCode::Left | KeyCode::Char('h') => Some((-1, 0)),
            KeyCode::Right | KeyCode::Char('l') => Some((1, 0)),
            KeyCode::Up | KeyCode::Char('k') => Some((0, 1)),
            KeyCode::Down | KeyCode::Char('j') => Some((0, -1)),
            _ => None,
        };
        if let Some((dc, dr)) = step {
            let Some(data) = self.data.clone() else {
                return Vec::new();
            };
            let Some((c, r)) = data.grid.position(j, z) else {
                return Vec::new();
            };
            let (c, r) = (c as i64 + dc, r as i64 + dr);
            if c < 0 || r < 0 {
                return Vec::new();
            }
            if let Some(cell) = data.grid.cell(c as usize, r as usize) {
                return self.open_zone(cell.joint, cell.zone);
            }
            return Vec::new();
        }
        match k.code {
            KeyCode::Esc => self.pane = Pane::Overview,
            KeyCode::Char('w') => self.open_form(),
            _ => {}
        }
        Vec::new()
    }

    fn form_open(&self) -> bool {
        self.pane == Pane::Zone && self.zone.as_ref().is_some_and(|z| z.whatif.is_some())
    }

    fn open_form(&mut self) {
        let Some(data) = self.data.clone() else {
            return;
        };
        let Some(view) = &mut self.zone else {
            return;
        };
        let date = view
            .planned
            .unwrap_or(data.run.plan.as_of)
            .max(data.run.plan.as_of);
        view.whatif = Some(WhatIfForm {
            field: Field::Supercool,
            supercool_c: 0.0,
            date,
            running: None,
            result: None,
            message: None,
        });
    }

    /// Keys of the what-if form; None lets the key through to the pane.
    fn on_form_key(&mut self, k: KeyEvent) -> Option<Vec<Command>> {
        let data = self.data.clone()?;
        let view = self.zone.as_mut()?;
        let (joint, zone) = (view.joint, view.zone);
        let form = view.whatif.as_mut()?;
        let s = &data.run.plan.settings;
        let running = form.running.is_some();
        let change = |form: &mut WhatIfForm, dir: i64, big: bool| {
            if running {
                return;
            }
            match form.field {
                Field::Supercool => {
                    let v = form.supercool_c + dir as f64 * s.supercooling_step_c;
                    // Snap to the step grid; the limit is the site's chillers'.
                    let v = (v / s.supercooling_step_c).round() * s.supercooling_step_c;
                    form.supercool_c = v.clamp(0.0, s.max_supercooling_c);
                }
                Field::Date => {
                    let d = form.date + Duration::days(dir * if big { 7 } else { 1 });
                    form.date = d.max(data.run.plan.as_of);
                }
            }
        };
        match k.code {
            KeyCode::Up | KeyCode::Char('k') | KeyCode::Down | KeyCode::Char('j') => {
                if !running {
                    form.field = match form.field {
                        Field::Supercool => Field::Date,
                        Field::Date => Field::Supercool,
                    };
                }
            }
            KeyCode::Left | KeyCode::Char('h') | KeyCode::Char('-') => change(form, -1, false),
            KeyCode::Right | KeyCode::Char('l') | KeyCode::Char('+') => change(form, 1, false),
            // Down the calendar is later: PgDn a week later, PgUp a week
            // earlier (the date only; the help and the keys line say so).
            KeyCode::PageDown if form.field == Field::Date => change(form, 1, true),
            KeyCode::PageUp if form.field == Field::Date => change(form, -1, true),
            KeyCode::Enter => {
                if running {
                    return Some(Vec::new());
                }
                form.running = Some(Running {
                    first_day: None,
                    day: 0.0,
                    end: 0.0,
                    cancelling: false,
                });
                form.message = None;
                return Some(vec![Command::RunWhatIf(WhatIf {
                    joint,
                    zone,
                    supercool_c: form.supercool_c,
                    date: form.date,
                })]);
            }
            KeyCode::Char('c') => {
                if let Some(r) = &mut form.running {
                    r.cancelling = true;
                    return Some(vec![Command::CancelWhatIf]);
                }
            }
            KeyCode::Char('s') => {
                if form.result.is_some() && !running {
                    return Some(vec![Command::SaveWhatIf]);
                }
                form.message = Some("nothing to save yet: run the what-if first (Enter)".into());
            }
            KeyCode::Esc => {
                if let Some(r) = &mut form.running {
                    r.cancelling = true;
                    return Some(vec![Command::CancelWhatIf]);
                }
                view.whatif = None;
            }
            _ => return None,
        }
        Some(Vec::new())
    }

    /// Opens the Zone pane on (joint, zone); a what-if running on another
    /// zone is cancelled.
    pub(super) fn open_zone(&mut self, joint: u32, zone: u32) -> Vec<Command> {
        let Some(data) = self.data.clone() else {
            return Vec::new();
        };
        let mut cmds = Vec::new();
        if let Some(v) = &self.zone {
            if (v.joint, v.zone) == (joint, zone) {
                self.pane = Pane::Zone;
                return cmds;
            }
            if self.running().is_some() {
                cmds.push(Command::CancelWhatIf);
                self.status = Some(format!(
                    "what-if on joint {} zone {} cancelled",
                    v.joint, v.zone
                ));
            }
        }
        if let Some(p) = data.grid.position(joint, zone) {
            self.cursor = p;
        }
        self.zone = Some(ZoneView {
            joint,
            zone,
            planned: data
                .run
                .schedules
                .grouting_of(ZoneId::new(joint, zone))
                .map(|g| g.planned),
            readiness: data.run.readiness(ZoneId::new(joint, zone)).cloned(),
            history: data.run.zone_history(ZoneId::new(joint, zone)),
            whatif: None,
        });
        self.pane = Pane::Zone;
        cmds
    }

    fn on_prompt_key(&mut self, k: KeyEvent) -> Vec<Command> {
        let Some(p) = &mut self.prompt else {
            return Vec::new();
        };
        match k.code {
            KeyCode::Esc => self.prompt = None,
            KeyCode::Backspace => {
                p.text.pop();
                p.error = None;
            }
            KeyCode::Char(c) if p.text.len() < 16 => {
                p.text.push(c);
                p.error = None;
            }
            KeyCode::Enter => {
                let text = p.text.clone();
                match self.jump(&text) {
                    Ok(cmds) => {
                        self.prompt = None;
                        return cmds;
                    }
                    Err(e) => {
                        if let Some(p) = &mut self.prompt {
                            p.error = Some(e);
                        }
                    }
                }
            }
            _ => {}
        }
        Vec::new()
    }

    /// `/5` goes to joint 5 on the overview, `/5 3` (or `5.3`, `5,3`,
    /// `j5 z3`) opens zone 3 of joint 5.
    fn jump(&mut self, text: &str) -> Result<Vec<Command>, String> {
        let data = self.data.clone().ok_or("nothing loaded yet")?;
        let nums: Vec<u32> = text
            .split(|c: char| !c.is_ascii_digit())
            .filter(|s| !s.is_empty())
            .map(|s| s.parse::<u32>().map_err(|_| format!("{s} is too large")))
            .collect::<Result<_, _>>()?;
        let grid = &data.grid;
        let joints = || {
            format!(
                "joints {}–{}",
                grid.joints.first().unwrap_or(&0),
                grid.joints.last().unwrap_or(&0)
            )
        };
        match nums[..] {
            [j] => {
                let c = grid
                    .joints
                    .iter()
                    .position(|&x| x == j)
                    .ok_or_else(|| format!("no joint {j} ({})", joints()))?;
                self.cursor.0 = c;
                self.pane = Pane::Overview;
                Ok(Vec::new())
            }
            [j, z] => {
                if !grid.joints.contains(&j) {
                    return Err(format!("no joint {j} ({})", joints()));
                }
                if grid
                    .position(j, z)
                    .and_then(|(c, r)| grid.cell(c, r))
                    .is_none()
                {
                    let zs = data.run.layout.zones_of(j);
                    return Err(format!(
                        "joint {j} has no zone {z} (zones {}–{})",
                        zs.first().unwrap_or(&0),
                        zs.last().unwrap_or(&0)
                    ));
                }
                Ok(self.open_zone(j, z))
            }
            _ => Err("type a joint number, or a joint and a zone: 5 or 5 3".into()),
        }
    }

    fn on_job(&mut self, j: JobEvent) {
        match j {
            JobEvent::PlanBaseline { day, end } => {
                if let Some(p) = &mut self.planning {
                    p.baseline = Some((day, end));
                }
            }
            JobEvent::PlanResimulation(what) => {
                if let Some(p) = &mut self.planning {
                    p.resimulations.push(what);
                }
            }
            JobEvent::Planned(data) => self.show(data),
            JobEvent::PlanFailed(e) => {
                if let Some(p) = &mut self.planning {
                    p.error = Some(e);
                }
            }
            JobEvent::WhatIfProgress { day, end } => {
                if let Some(r) = self.running_mut() {
                    r.first_day.get_or_insert(day);
                    r.day = day;
                    r.end = end;
                }
            }
            JobEvent::WhatIfDone(outcome) => {
                let key = outcome.what_if.zone_id();
                if let Some(f) = self.form_of(key) {
                    f.running = None;
                    f.message = outcome.not_applied.clone();
                    f.result = Some(outcome);
                }
            }
            JobEvent::WhatIfCancelled => {
                if let Some(f) = self.zone.as_mut().and_then(|z| z.whatif.as_mut()) {
                    f.running = None;
                    f.message = Some("cancelled".into());
                }
                self.status = Some("what-if cancelled".into());
            }
            JobEvent::WhatIfFailed(e) => {
                if let Some(f) = self.zone.as_mut().and_then(|z| z.whatif.as_mut()) {
                    f.running = None;
                    f.message = Some(format!("failed: {e}"));
                }
            }
            JobEvent::Saved(path) => {
                let text = format!("saved {}", path.display());
                if let Some(f) = self.zone.as_mut().and_then(|z| z.whatif.as_mut()) {
                    f.message = Some(text.clone());
                }
                self.status = Some(text);
            }
            JobEvent::SaveFailed(e) => {
                let text = format!("not saved: {e}");
                if let Some(f) = self.zone.as_mut().and_then(|z| z.whatif.as_mut()) {
                    f.message = Some(text.clone());
                }
                self.status = Some(text);
            }
        }
    }

    fn running_mut(&mut self) -> Option<&mut Running> {
        self.zone.as_mut()?.whatif.as_mut()?.running.as_mut()
    }

    fn form_of(&mut self, key: ZoneId) -> Option<&mut WhatIfForm> {
        let z = self.zone.as_mut()?;
        if ZoneId::new(z.joint, z.zone) != key {
            return None;
        }
        z.whatif.as_mut()
    }
}
