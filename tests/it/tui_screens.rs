//! The TUI without a terminal: every screen drawn at 80×24 into ratatui's
//! `TestBackend` on the small dam's plan (snapshots under `snapshots/`), key
//! sequences driving the same `Session` the terminal loop drives, a what-if
//! re-simulated and saved, and one cancelled.

use std::time::Duration;

use ratatui::backend::TestBackend;
use ratatui::crossterm::event::{KeyCode, KeyEvent, KeyModifiers};
use ratatui::style::Color;
use ratatui::Terminal;

use groutready::planner::edit::first_change;
use groutready::planner::Verdict;
use groutready::schedule;
use groutready::tui::{App, Event, JobEvent, Pane, RunData, Session};

use crate::common;

/// The small dam's plan, opened (what-ifs save into `dir` when given).
fn session(dir: Option<&std::path::Path>, color: bool) -> Session {
    let p = common::small_plan();
    assert_eq!(p.output.status.code(), Some(0), "{}", p.stderr());
    let mut data = RunData::load(&p.out).unwrap();
    if let Some(d) = dir {
        data.dir = d.to_path_buf();
    }
    Session::open(data, color)
}

fn draw(app: &App, w: u16, h: u16) -> Terminal<TestBackend> {
    let mut t = Terminal::new(TestBackend::new(w, h)).unwrap();
    t.draw(|f| f.render_widget(app, f.area())).unwrap();
    t
}

/// The screen as text, one line per row, trailing blanks cut.
fn screen(app: &App, w: u16, h: u16) -> String {
    let t = draw(app, w, h);
    let buf = t.backend().buffer();
    let mut s = String::new();
    for y in 0..h {
        let mut line = String::new();
        for x in 0..w {
            line.push_str(buf[(x, y)].symbol());
        }
        s.push_str(line.trim_end());
        s.push('\n');
    }
    s
}

fn keys(s: &mut Session, keys: &str) {
    for c in keys.chars() {
        s.handle(Event::char(c));
    }
}

fn key(s: &mut Session, code: KeyCode) {
    s.handle(Event::key(code));
}

/// `/` jump to a zone: the screen a site engineer gets by typing `/1 4⏎`.
fn open(s: &mut Session, joint: u32, zone: u32) {
    keys(s, &format!("/{joint} {zone}"));
    key(s, KeyCode::Enter);
    let z = s.app.zone.as_ref().expect("a zone is open");
    assert_eq!((z.joint, z.zone, s.app.pane), (joint, zone, Pane::Zone));
}

#[test]
fn overview_screen() {
    let s = session(None, true);
    let text = screen(&s.app, 80, 24);
    // The cursor starts on the first flagged zone.
    assert_eq!(s.app.cursor, (1, 1));
    assert!(text.contains("8 of 12 to grout flagged"), "{text}");
    insta::assert_snapshot!("overview", text);
}

#[test]
fn flagged_list_screen_and_enter_opens_the_zone() {
    let mut s = session(None, true);
    key(&mut s, KeyCode::Tab);
    assert_eq!(s.app.pane, Pane::Flagged);
    let text = screen(&s.app, 80, 24);
    // Each flagged zone with the rules it fails and its remedy in brief.
    assert!(text.contains("Fails") && text.contains("Remedy"), "{text}");
    let j1z4 = text
        .lines()
        .find(|l| l.contains("    1    4 2024-09-13"))
        .unwrap_or_else(|| panic!("{text}"));
    assert!(j1z4.contains("supercool 1.25 °C"), "{j1z4}");
    insta::assert_snapshot!("flagged", text);
    keys(&mut s, "jj");
    key(&mut s, KeyCode::Enter);
    let z = s.app.zone.as_ref().unwrap();
    // The third flagged zone by planned date: joint 1, zone 2 (3 July).
    assert_eq!((z.joint, z.zone, s.app.pane), (1, 2, Pane::Zone));
}

#[test]
fn zone_detail_screen() {
    let mut s = session(None, true);
    open(&mut s, 1, 4);
    let text = screen(&s.app, 80, 24);
    assert!(text.contains("supercool 1.25 °C"), "{text}");
    // The rules in words: the zone below's order, the temperature's limit
    // as closure + tolerance; the charts with the minimum, the remedy's
    // verified run and the warmer block against the closure.
    assert!(text.contains("zone below   grouted 36 d before"), "{text}");
    assert!(text.contains("warmer block 14.5 °C, max 14.0"), "{text}");
    assert!(text.contains("  = closure 13.0 + tolerance 1.0"), "{text}");
    assert!(!text.contains("≥ 0 d"), "{text}");
    insta::assert_snapshot!("zone_detail", text);
    let wide = screen(&s.app, 110, 30);
    for name in ["min", "remedy", "warmer block", "closure 13.0", "limit 14"] {
        assert!(wide.contains(name), "{name} missing:\n{wide}");
    }
    insta::assert_snapshot!("zone_detail_wide", wide);
    // Narrower than the zone's header: it wraps rather than being cut.
    let narrow = screen(&s.app, 60, 24);
    assert!(narrow.contains("not groutable"), "{narrow}");
}

#[test]
fn help_screen_opens_and_closes() {
    let mut s = session(None, true);
    keys(&mut s, "?");
    let text = screen(&s.app, 80, 24);
    assert!(text.contains("save the schedules as a CSV set"), "{text}");
    insta::assert_snapshot!("help", text);
    key(&mut s, KeyCode::Esc);
    assert!(!s.app.help);
    assert!(!s.app.quit);
}

#[test]
fn planning_screen_shows_progress_and_failure() {
    let mut app = App::planning("Small dam with joints", true);
    app.update(Event::Job(JobEvent::PlanBaseline {
        day: 90.0,
        end: 180.0,
    }));
    let text = screen(&app, 80, 24);
    assert!(text.contains("baseline: day 90 of 180"), "{text}");
    insta::assert_snapshot!("planning", text);
    app.update(Event::Job(JobEvent::PlanResimulation(
        "supercooling 2 zones by 3.00 °C".into(),
    )));
    app.update(Event::Job(JobEvent::PlanFailed("no pours.csv".into())));
    let text = screen(&app, 80, 24);
    assert!(
        text.contains("The plan failed:") && text.contains("no pours.csv"),
        "{text}"
    );
    app.update(Event::char('q'));
    assert!(app.quit);

    // A scene with opt-in approximations says which while it is planned.
    let mut app = App::planning("Small dam with joints", true);
    app.planning.as_mut().unwrap().approximations =
        vec![groutready::scene::Approximation::LongerSteps { max_days: 3 }];
    let text = screen(&app, 80, 24);
    assert!(
        text.contains("With opt-in approximations of the mechanics:")
            && text.contains("time.mechanics_max_step_days = 3"),
        "{text}"
    );
    assert!(
        text.contains("baseline") || text.contains("reading the inputs"),
        "{text}"
    );
}

#[test]
fn whatif_supercooling_is_resimulated_shown_beside_the_plan_and_saved() {
    let tmp = tempfile::tempdir().unwrap();
    let mut s = session(Some(tmp.path()), true);
    open(&mut s, 1, 4);
    keys(&mut s, "w");
    // Five steps of 0.25 °C: the plan's own remedy for this zone.
    for _ in 0..5 {
        key(&mut s, KeyCode::Right);
    }
    key(&mut s, KeyCode::Enter);
    assert!(
        s.app.running().is_some(),
        "the what-if runs in the background"
    );
    // The UI answers while it runs: the screen draws, keys are taken.
    let busy = screen(&s.app, 80, 24);
    assert!(
        busy.contains("re-simulating") || busy.contains("c cancel"),
        "{busy}"
    );
    assert!(
        s.wait_idle(Duration::from_secs(300)),
        "the what-if did not finish"
    );
    let form = s.app.zone.as_ref().unwrap().whatif.as_ref().unwrap();
    let result = form.result.as_ref().expect("a result");
    assert_eq!(result.what_if.supercool_c, 1.25);
    assert!(result.not_applied.is_none(), "{:?}", result.not_applied);
    let plan = s.app.zone.as_ref().unwrap().readiness.clone().unwrap();
    assert_eq!(plan.verdict, Verdict::NotGroutable);
    assert_eq!(
        result.readiness.verdict,
        Verdict::Groutable,
        "{}",
        result.readiness.reasons()
    );
    // Cooler than planned on the planned date.
    let hottest =
        |z: &groutready::planner::ZoneReadiness| z.temp_a_c.unwrap().max(z.temp_b_c.unwrap());
    assert!(hottest(&result.readiness) < hottest(&plan) - 0.3);
    let seconds = result.seconds;
    assert!(seconds > 0.0);
    // Wall time is not reproducible: the snapshot shows 0.0 s.
    let form = s.app.zone.as_mut().unwrap().whatif.as_mut().unwrap();
    form.result.as_mut().unwrap().seconds = 0.0;
    let text = screen(&s.app, 80, 24);
    assert!(text.contains("what-if  ✓ groutable"), "{text}");
    assert!(text.contains("re-simulated in 0.0 s"), "{text}");
    insta::assert_snapshot!("whatif", text);

    keys(&mut s, "s");
    let saved = tmp.path().join("whatif/j1-z4-sc1.25-2024-09-13");
    assert!(saved.join("cooling.csv").is_file(), "{:?}", s.app.status);
    let data = s.app.data.clone().unwrap();
    let edited = schedule::load(&saved).unwrap();
    schedule::check_against(&edited, &data.run.layout).unwrap();
    let changed = first_change(&data.run.schedules, &edited).expect("the cooling changed");
    assert!(
        changed >= data.run.plan.as_of,
        "the past is not re-cooled: {changed}"
    );
    assert_eq!(edited.grouting, data.run.schedules.grouting);
    // Nothing half-written beside it.
    let names: Vec<String> = std::fs::read_dir(tmp.path().join("whatif"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(names, vec!["j1-z4-sc1.25-2024-09-13".to_string()]);
}

#[test]
fn whatif_can_be_cancelled_and_the_form_stays_usable() {
    let mut s = session(None, true);
    open(&mut s, 2, 4);
    keys(&mut s, "wj");
    // A week later (PgDn: down the calendar): a re-simulation from the
    // checkpoint before that week.
    key(&mut s, KeyCode::PageDown);
    key(&mut s, KeyCode::Enter);
    assert!(s.app.running().is_some());
    keys(&mut s, "c");
    assert!(s.app.running().unwrap().cancelling);
    assert!(s.wait_idle(Duration::from_secs(120)));
    let form = s.app.zone.as_ref().unwrap().whatif.as_ref().unwrap();
    assert!(form.result.is_none());
    assert_eq!(form.message.as_deref(), Some("cancelled"));
    assert!(screen(&s.app, 80, 24).contains("cancelled"));
    // The form is still there and closes with Esc; a second Esc goes back.
    key(&mut s, KeyCode::Esc);
    assert!(s.app.zone.as_ref().unwrap().whatif.is_none());
    key(&mut s, KeyCode::Esc);
    assert_eq!(s.app.pane, Pane::Overview);
}

#[test]
fn keys_move_jump_switch_panes_and_quit() {
    let mut s = session(None, true);
    assert_eq!(s.app.cursor, (1, 1)); // joint 2, zone 2
    keys(&mut s, "hk");
    assert_eq!(s.app.cursor, (0, 2)); // joint 1, zone 3: up is up the dam
    key(&mut s, KeyCode::Down);
    key(&mut s, KeyCode::Right);
    key(&mut s, KeyCode::Right);
    assert_eq!(s.app.cursor, (2, 1));
    // Clamped at the edges.
    for _ in 0..9 {
        keys(&mut s, "l");
    }
    assert_eq!(s.app.cursor.0, 3);
    key(&mut s, KeyCode::Enter);
    let z = s.app.zone.as_ref().unwrap();
    assert_eq!((z.joint, z.zone), (4, 2));
    // Arrows in the zone go to the neighbouring zone.
    key(&mut s, KeyCode::Up);
    let z = s.app.zone.as_ref().unwrap();
    assert_eq!((z.joint, z.zone), (4, 3));
    // Tab cycles the panes, Shift-Tab back.
    key(&mut s, KeyCode::Tab);
    assert_eq!(s.app.pane, Pane::Overview);
    key(&mut s, KeyCode::Tab);
    assert_eq!(s.app.pane, Pane::Flagged);
    s.handle(Event::Key(KeyEvent::new(
        KeyCode::BackTab,
        KeyModifiers::SHIFT,
    )));
    assert_eq!(s.app.pane, Pane::Overview);
    // A joint alone moves the overview's cursor.
    keys(&mut s, "/3");
    key(&mut s, KeyCode::Enter);
    assert_eq!((s.app.cursor.0, s.app.pane), (2, Pane::Overview));
    // A wrong number says what exists, and the prompt stays open.
    keys(&mut s, "/9");
    key(&mut s, KeyCode::Enter);
    let text = screen(&s.app, 80, 24);
    assert!(text.contains("no joint 9 (joints 1–4)"), "{text}");
    key(&mut s, KeyCode::Backspace);
    keys(&mut s, "2 9");
    key(&mut s, KeyCode::Enter);
    assert!(screen(&s.app, 80, 24).contains("joint 2 has no zone 9 (zones 1–7)"));
    key(&mut s, KeyCode::Esc);
    assert!(s.app.prompt.is_none());
    // A zone not poured yet opens too, and says so.
    open(&mut s, 3, 6);
    assert!(screen(&s.app, 80, 24).contains("Not in this plan"));
    s.handle(Event::Key(KeyEvent::new(
        KeyCode::Char('c'),
        KeyModifiers::CONTROL,
    )));
    assert!(s.app.quit);
}

#[test]
fn no_color_draws_symbols_without_colours() {
    for color in [true, false] {
        let s = session(None, color);
        let t = draw(&s.app, 80, 24);
        let buf = t.backend().buffer();
        let fg: Vec<Color> = buf.content().iter().map(|c| c.fg).collect();
        let coloured = fg.iter().filter(|&&c| c != Color::Reset).count();
        if color {
            assert!(fg.contains(&Color::Red), "the flagged cells are red");
        } else {
            assert_eq!(coloured, 0, "NO_COLOR: no colour at all");
        }
        // Either way each state reads from its symbol.
        let text = screen(&s.app, 80, 24);
        for sym in ["✗0.65", "✓1.28", "■0.24", "·"] {
            assert!(text.contains(sym), "{sym} missing:\n{text}");
        }
    }
}

#[test]
fn every_pane_draws_at_any_size() {
    let mut s = session(None, true);
    for (w, h) in [(80, 24), (60, 16), (132, 40), (20, 6), (1, 1)] {
        for k in ["1", "2", "?", "?"] {
            keys(&mut s, k);
            draw(&s.app, w, h);
        }
        open(&mut s, 1, 4);
        keys(&mut s, "w");
        draw(&s.app, w, h);
        key(&mut s, KeyCode::Esc);
        keys(&mut s, "1");
    }
    // Too narrow for every joint: the grid follows the cursor sideways, and
    // says there is more to the left.
    keys(&mut s, "1llllll");
    let text = screen(&s.app, 30, 24);
    assert!(
        text.contains("J4") && !text.contains("J1 ") && text.contains('◀'),
        "{text}"
    );
    keys(&mut s, "hhhhhh");
    let text = screen(&s.app, 30, 24);
    assert!(text.contains("J1") && text.contains('▶'), "{text}");
    // Wide enough, the whole dam is on one screen with nothing cut.
    let text = screen(&s.app, 132, 40);
    assert!(text.contains("J1    J2    J3    J4"), "{text}");
    assert!(!text.contains('▶'));
}

#[test]
fn whatif_supercools_a_running_stage_from_the_as_of_date() {
    let mut s = session(None, true);
    // Joint 2 zone 2's cooling started before 1 June and runs past its
    // date: the what-if gives it colder water from 1 June (issue 15).
    open(&mut s, 2, 2);
    let zone = s.app.zone.as_ref().unwrap();
    let before = zone.readiness.as_ref().unwrap().temp_a_c.unwrap();
    keys(&mut s, "w++++");
    key(&mut s, KeyCode::Enter);
    assert!(s.wait_idle(Duration::from_secs(300)));
    let form = s.app.zone.as_ref().unwrap().whatif.as_ref().unwrap();
    let result = form.result.as_ref().expect("a result");
    assert!(result.not_applied.is_none(), "{:?}", result.not_applied);
    let after = result.readiness.temp_a_c.unwrap();
    // 1 °C colder water for the month left: 0.35 °C cooler on its date.
    assert!(after < before - 0.2, "{before} °C → {after} °C");
}

#[test]
fn every_legend_state_has_its_cell_symbol_and_colour() {
    use groutready::tui::grid::{CellState, Grid};
    let p = common::small_plan();
    let mut data = RunData::load(&p.out).unwrap();
    let count = |g: &Grid| CellState::ALL.map(|s| g.count(s));
    // As planned: 8 flagged, 4 groutable, 4 grouted, zones 5–7 not poured.
    assert_eq!(count(&data.grid), [8, 0, 4, 4, 0, 0, 12]);
    // A grouted zone that re-opened, a marginal one, and a later as-of date
    // by which zones 5–7 are poured but beyond the plan.
    let plan = &mut data.run.plan;
    plan.zones.iter_mut().find(|z| z.history).unwrap().reopened = Some(common::date(2024, 6, 20));
    plan.zones
        .iter_mut()
        .find(|z| !z.history && z.verdict == Verdict::Groutable)
        .unwrap()
        .verdict = Verdict::Marginal;
    plan.as_of = common::date(2025, 6, 1);
    data.grid = Grid::new(&data.run.layout, &data.run.schedules, &data.run.plan);
    assert_eq!(count(&data.grid), [8, 1, 3, 3, 1, 12, 0]);
    let s = Session::open(data, true);
    let t = draw(&s.app, 80, 24);
    let text = screen(&s.app, 80, 24);
    let buf = t.backend().buffer();
    // Not poured is drawn in the first grid (zones 5–7 before June 2024).
    for state in CellState::ALL
        .into_iter()
        .filter(|&s| s != CellState::NotPoured)
    {
        let sym = state.symbol();
        // The first cell of the grid (rows 3–17: not the header or legend).
        let (x, y) = (3..18u16)
            .flat_map(|y| (5..80u16).map(move |x| (x, y)))
            .find(|&(x, y)| buf[(x, y)].symbol() == sym)
            .unwrap_or_else(|| panic!("{sym} missing:\n{text}"));
        let want = match state {
            CellState::NotGroutable => Color::Red,
            CellState::Marginal => Color::Yellow,
            CellState::Groutable => Color::Green,
            CellState::Grouted => Color::Blue,
            CellState::Reopened => Color::Magenta,
            CellState::Later | CellState::NotPoured => Color::DarkGray,
        };
        assert_eq!(buf[(x, y)].fg, want, "{sym} at {x},{y}");
    }
}

#[test]
fn whatif_fields_stay_within_the_site_limits() {
    let mut s = session(None, true);
    open(&mut s, 1, 4);
    keys(&mut s, "w");
    for _ in 0..20 {
        key(&mut s, KeyCode::Right);
    }
    let form = |s: &Session| s.app.zone.as_ref().unwrap().whatif.clone().unwrap();
    // The chillers' limit, on the step grid.
    assert_eq!(form(&s).supercool_c, 3.0);
    keys(&mut s, "-");
    assert_eq!(form(&s).supercool_c, 2.75);
    for _ in 0..20 {
        key(&mut s, KeyCode::Left);
    }
    assert_eq!(form(&s).supercool_c, 0.0);
    // PgUp/PgDn are for the date only.
    key(&mut s, KeyCode::PageDown);
    assert_eq!(form(&s).supercool_c, 0.0);
    // The date: a day per arrow, a week per page (PgDn later, PgUp
    // earlier, as the keys line says), never before the as-of date.
    keys(&mut s, "j");
    let text = screen(&s.app, 80, 24);
    assert!(text.contains("PgUp/PgDn −/+ week"), "{text}");
    key(&mut s, KeyCode::Right);
    key(&mut s, KeyCode::PageDown);
    assert_eq!(form(&s).date, common::date(2024, 9, 21));
    for _ in 0..30 {
        key(&mut s, KeyCode::PageUp);
    }
    assert_eq!(form(&s).date, common::date(2024, 6, 1));
    // Nothing to save before a run.
    keys(&mut s, "s");
    let msg = form(&s).message.unwrap();
    assert!(msg.contains("nothing to save yet"), "{msg}");
}

#[test]
fn joint_meter_readings_are_drawn_on_the_zone_chart() {
    use groutready::planner::MeterComparison;
    let p = common::small_plan();
    let mut data = RunData::load(&p.out).unwrap();
    data.run.plan.meters = [(7, 1, 0.40, 0.52), (8, 15, 1.20, 1.28)]
        .into_iter()
        .map(|(m, d, measured, predicted)| MeterComparison {
            joint: 1,
            zone: 4,
            point: groutready::vocab::ZonePoint::Center,
            date: common::date(2024, m, d),
            measured_mm: measured,
            predicted_mm: Some(predicted),
        })
        .collect();
    let mut s = Session::open(data, false);
    open(&mut s, 1, 4);
    let text = screen(&s.app, 80, 24);
    assert!(text.contains("█meter"), "{text}");
    assert!(text.contains("2 meter readings"), "{text}");
    assert!(text.contains("+0.10 mm"), "{text}");
    // Two readings drawn inside the aperture chart (left of the side panel).
    let drawn: usize = text
        .lines()
        .skip(4)
        .take(8)
        .map(|l| l.chars().take(42).filter(|&c| c == '█').count())
        .sum();
    assert_eq!(drawn, 2, "{text}");
}

/// A what-if after the first makes its mechanics on the frame the first
/// one made (`Runner::with_frame`): the same answer to the bit.
#[test]
fn a_second_what_if_on_the_kept_frame_gives_the_first_ones_answer() {
    let p = common::small_plan();
    assert_eq!(p.output.status.code(), Some(0), "{}", p.stderr());
    let data = RunData::load(&p.out).unwrap();
    let zone = data.run.plan.zones.iter().find(|z| !z.history).unwrap();
    let w = groutready::planner::whatif::WhatIf {
        joint: zone.joint,
        zone: zone.zone,
        supercool_c: 1.0,
        date: zone.planned,
    };
    let first = data.run.what_if(&w, None, &mut |_, _| {}).unwrap();
    let second = data.run.what_if(&w, None, &mut |_, _| {}).unwrap();
    println!(
        "what-if on joint {} zone {}: {:.2} then {:.2} s",
        w.joint, w.zone, first.seconds, second.seconds
    );
    assert!(first.not_applied.is_none(), "{:?}", first.not_applied);
    // (Debug text, not ==: a history holds NaN where nothing is known)
    assert_eq!(
        format!("{:?}", first.readiness),
        format!("{:?}", second.readiness)
    );
    assert_eq!(
        format!("{:?}", first.history),
        format!("{:?}", second.history)
    );
}

/// A plan computed with opt-in approximations of the mechanics says so in
/// the header (the reports name them); the small dam's exact plan does not.
#[test]
fn the_header_marks_a_plan_with_approximate_mechanics() {
    let p = common::small_plan();
    assert_eq!(p.output.status.code(), Some(0), "{}", p.stderr());
    let mut data = RunData::load(&p.out).unwrap();
    assert!(data.run.plan.approximations.is_empty());
    data.run.plan.approximations = vec![groutready::scene::Approximation::MergedPours];
    let s = Session::open(data, true);
    let text = screen(&s.app, 120, 24);
    let header = text.lines().next().unwrap();
    assert!(header.ends_with(" · ! approximate mechanics"), "{text}");
    let exact = session(None, true);
    assert!(!screen(&exact.app, 120, 24).contains("approximate"));
}
