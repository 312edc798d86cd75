//! Progress of long runs. On a terminal it is a bar. When stderr is not a
//! terminal (a run left with its output in a log: the large arch's whole
//! construction takes hours) the bar is hidden and a line is printed at
//! each tenth of the simulated days and at least every
//! [`LOG_EVERY_SECONDS`], with the rate since the last line and the time
//! left at that rate, so the log says how far the run got and when it
//! should end.

use std::sync::Mutex;

use indicatif::{ProgressBar, ProgressStyle};

/// Longest interval between two log lines \[s\]: the Xiaowan-like arch's
/// tenths are 35–60 min apart.
pub const LOG_EVERY_SECONDS: f64 = 600.0;

/// A progress bar, or the log lines that stand in for it.
pub struct Progress {
    bar: ProgressBar,
    log: Mutex<LogLines>,
}

pub fn bar(what: &str) -> Progress {
    let bar = ProgressBar::new(1000);
    bar.set_style(
        ProgressStyle::with_template("{msg} [{bar:40}] {percent:>3}% day {prefix} ({elapsed})")
            .expect("static template")
            .progress_chars("=> "),
    );
    bar.set_message(what.to_string());
    Progress {
        bar,
        log: Mutex::new(LogLines::default()),
    }
}

impl Progress {
    /// A stage of work with no day count of its own (a plan's remedy
    /// re-simulations): the bar becomes a spinner saying `what`, where it
    /// would show the last run's days; in a log, a line.
    pub fn stage(&self, what: String) {
        if self.bar.is_hidden() {
            eprintln!("{what}");
        }
        self.bar.set_style(
            ProgressStyle::with_template("{spinner} {msg} ({elapsed})").expect("static template"),
        );
        self.bar.set_message(what);
        self.bar
            .enable_steady_tick(std::time::Duration::from_millis(120));
    }

    /// Runs `f` (which prints) with the bar out of the way.
    pub fn suspend<R>(&self, f: impl FnOnce() -> R) -> R {
        self.bar.suspend(f)
    }

    pub fn finish_and_clear(&self) {
        self.bar.finish_and_clear();
    }
}

pub fn update(p: &Progress, day: f64, end: f64) {
    let bar = &p.bar;
    if end > 0.0 {
        bar.set_position(((day / end) * 1000.0) as u64);
        if bar.is_hidden() {
            let secs = bar.elapsed().as_secs_f64();
            let mut log = p.log.lock().unwrap_or_else(|e| e.into_inner());
            if let Some(line) = log.line(day, end, secs) {
                eprintln!("{}: {line}", bar.message());
            }
        }
    }
    bar.set_prefix(format!("{day:.0}/{end:.0}"));
}

/// When the last log line was printed: its day and second.
#[derive(Debug, Default)]
pub struct LogLines {
    last: Option<(f64, f64)>,
}

impl LogLines {
    /// The line to print at `day` of `end` after `secs` seconds, if one is
    /// due: a tenth of the days crossed since the last line (the first
    /// update, e.g. a run continued from a restart point, prints too), or
    /// [`LOG_EVERY_SECONDS`] passed with the days moving.
    pub fn line(&mut self, day: f64, end: f64, secs: f64) -> Option<String> {
        let tenth = |d: f64| (10.0 * d / end).floor();
        let due = match self.last {
            None => true,
            Some((d0, s0)) => {
                tenth(day) > tenth(d0) || (secs - s0 >= LOG_EVERY_SECONDS && day > d0)
            }
        };
        if !due {
            return None;
        }
        let since = self.last.replace((day, secs));
        let mut line = format!(
            "day {day:.0} of {end:.0} ({:.0} %), {secs:.0} s",
            (100.0 * day / end).floor()
        );
        if let Some((d0, s0)) = since.filter(|&(d0, _)| day > d0) {
            let days = day - d0;
            let rate = (secs - s0) / days;
            let digits = if rate < 1.0 { 2 } else { 1 };
            line += &format!("; {rate:.digits$} s a day over the last {days:.0} days");
            if day < end {
                let left = duration_text(rate * (end - day));
                line += &format!(", about {left} left at that rate");
            }
        }
        Some(line)
    }
}

/// Seconds as "2 h 05 min", "12 min" or "40 s".
fn duration_text(secs: f64) -> String {
    let s = secs.max(0.0).round() as u64;
    match s {
        0..=59 => format!("{s} s"),
        60..=3599 => format!("{} min", s / 60),
        _ => format!("{} h {:02} min", s / 3600, s % 3600 / 60),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_line_at_each_tenth_and_every_ten_minutes_with_the_rate_and_time_left() {
        let mut log = LogLines::default();
        // a continued run's first update: where it starts, no rate yet
        assert_eq!(
            log.line(534.0, 1182.0, 5.0).as_deref(),
            Some("day 534 of 1182 (45 %), 5 s")
        );
        assert_eq!(log.line(560.0, 1182.0, 300.0), None);
        // ten minutes on: a line with the rate since the last one
        let line = log.line(585.0, 1182.0, 615.0).expect("ten minutes passed");
        assert_eq!(
            line,
            "day 585 of 1182 (49 %), 615 s; 12.0 s a day over the last 51 days, \
             about 1 h 59 min left at that rate"
        );
        // the tenth crossed before ten minutes have passed
        let line = log.line(592.0, 1182.0, 700.0).expect("50 % crossed");
        assert!(
            line.starts_with("day 592 of 1182 (50 %), 700 s; 12.1 s a day over the last 7 days")
        );
        // stuck on one day (a long contact step): no line for lack of progress
        assert_eq!(log.line(592.0, 1182.0, 2000.0), None);
        // the end: the rate, nothing left
        let line = log.line(1182.0, 1182.0, 2590.0).expect("the last tenth");
        assert_eq!(
            line,
            "day 1182 of 1182 (100 %), 2590 s; 3.2 s a day over the last 590 days"
        );
        // a quick run: a rate below a second keeps two decimals
        let mut quick = LogLines::default();
        quick.line(0.0, 400.0, 0.0);
        let line = quick.line(40.0, 400.0, 1.0).expect("10 %");
        assert!(line.contains("0.03 s a day"), "{line}");
    }

    #[test]
    fn durations_read_as_a_site_engineer_writes_them() {
        assert_eq!(duration_text(40.2), "40 s");
        assert_eq!(duration_text(754.0), "12 min");
        assert_eq!(duration_text(7500.0), "2 h 05 min");
        assert_eq!(duration_text(-3.0), "0 s");
    }
}
