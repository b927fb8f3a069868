//! What the commands tell a user while and after they run: a progress bar on a terminal, and
//! warnings.

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::time::Duration;

/// A progress bar on stderr that shows itself only on a terminal and only once a run has
/// taken a second.
pub fn progress_bar(length: u64) -> ProgressBar {
    let bar = ProgressBar::with_draw_target(Some(length), ProgressDrawTarget::hidden());
    bar.set_style(ProgressStyle::with_template("{elapsed_precise} [{bar:40}] {pos}/{len} {msg}").expect("a valid template").progress_chars("=> "));
    let shown = bar.clone();
    std::thread::spawn(move || {
        std::thread::sleep(Duration::from_secs(1));
        if !shown.is_finished() {
            shown.set_draw_target(ProgressDrawTarget::stderr());
        }
    });
    bar
}

/// What a run that DOPRI5 or DOP853 finds stiff tells the user.
pub fn stiff_warning(method: &str, t: f64) -> String {
    format!("warning: {method} {}: the stiff method may be much faster, `--method ros23`", runtime::integrate::stiffness_note(t))
}
