//! Progress on a terminal: a spinner naming the step under way and the time it has taken, for the
//! steps that can take seconds (loading and generating scenes, building structures, statistics,
//! rendering frames). Hidden when standard error is not a terminal.

use std::time::Duration;

use indicatif::{ProgressBar, ProgressStyle};

/// A step in progress; the spinner goes when it is dropped.
pub struct Step(ProgressBar);

/// Starts showing `message` with a spinner and the time elapsed.
pub fn step(message: impl Into<String>) -> Step {
    let bar = ProgressBar::new_spinner();
    if let Ok(style) = ProgressStyle::with_template("{spinner} {msg} ({elapsed})") {
        bar.set_style(style);
    }
    bar.set_message(message.into());
    bar.enable_steady_tick(Duration::from_millis(120));
    Step(bar)
}

impl Drop for Step {
    fn drop(&mut self) {
        self.0.finish_and_clear();
    }
}
