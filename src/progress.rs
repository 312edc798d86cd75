//! Progress bars for long runs. When stderr is not a terminal (a run left
//! with its output in a log: the large arch's whole construction takes
//! hours) the bar is hidden and a line is printed at each tenth of the
//! simulated days instead, so the log says how far the run got.

use indicatif::{ProgressBar, ProgressStyle};

pub fn bar(what: &str) -> ProgressBar {
    let bar = ProgressBar::new(1000);
    bar.set_style(
        ProgressStyle::with_template("{msg} [{bar:40}] {percent:>3}% day {prefix} ({elapsed})")
            .expect("static template")
            .progress_chars("=> "),
    );
    bar.set_message(what.to_string());
    bar
}

pub fn update(bar: &ProgressBar, day: f64, end: f64) {
    if end > 0.0 {
        let before = bar.position();
        let now = ((day / end) * 1000.0) as u64;
        bar.set_position(now);
        if bar.is_hidden() && now / 100 > before / 100 {
            eprintln!(
                "{}: day {day:.0} of {end:.0} ({} %), {:.0} s",
                bar.message(),
                now / 10,
                bar.elapsed().as_secs_f64()
            );
        }
    }
    bar.set_prefix(format!("{day:.0}/{end:.0}"));
}
