//! Progress bars for long runs (hidden when stderr is not a terminal, so
//! unattended runs and CI logs stay clean).

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
        bar.set_position(((day / end) * 1000.0) as u64);
    }
    bar.set_prefix(format!("{day:.0}/{end:.0}"));
}
