//! A spinner on stderr for single steps that can take more than a second
//! (reading, interpolating or measuring a large volume). indicatif draws
//! nothing when stderr is not a terminal, so scripts and tests see no noise.
use indicatif::{ProgressBar, ProgressStyle};
use std::time::Duration;

/// A spinner showing `msg` and the elapsed time until it is dropped or
/// finished; it clears its line when done.
pub fn spinner(msg: &str) -> ProgressBar {
    let bar = ProgressBar::new_spinner();
    bar.set_style(
        ProgressStyle::with_template("{spinner} {msg} ({elapsed})").expect("valid template"),
    );
    bar.set_message(msg.to_string());
    bar.enable_steady_tick(Duration::from_millis(120));
    bar
}
