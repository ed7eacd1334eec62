//! The progress bar of `hil run` and of the worker pool (sweep, bench, faults).

/// A progress bar on stderr (`[####    ]  42%  {what}`) for `total` steps, redrawn in place
/// (at most 20 times a second) if `show`, hidden otherwise; `what` is an indicatif template
/// after the percentage, which may also use `{rate}` (steps per second) and `{left}` (the
/// estimated time left, `1:02:03`). Shared by `hil run` and `hil sweep`; [`end_progress`]
/// ends its line.
pub fn progress_bar(total: u64, show: bool, what: &str) -> indicatif::ProgressBar {
    use indicatif::{ProgressState, ProgressStyle};
    if !show {
        return indicatif::ProgressBar::hidden();
    }
    let style = ProgressStyle::with_template(&format!("[{{bar:40}}] {{percent:>3}}%  {what}"))
        .unwrap_or_else(|_| ProgressStyle::default_bar())
        .progress_chars("## ")
        .with_key("rate", |s: &ProgressState, w: &mut dyn std::fmt::Write| {
            let _ = write!(w, "{:.1}", s.per_sec());
        })
        .with_key("left", |s: &ProgressState, w: &mut dyn std::fmt::Write| {
            let _ = write!(w, "{}", crate::sweep::pool::clock(s.eta().as_secs_f64()));
        });
    indicatif::ProgressBar::new(total).with_style(style)
}

/// Leaves the bar as it is and ends its line.
pub fn end_progress(bar: &indicatif::ProgressBar) {
    if !bar.is_hidden() {
        bar.abandon();
        eprintln!();
    }
}
