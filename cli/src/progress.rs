//! The progress bar of a simulation, on stderr: simulated time against the end
//! time, and the step count. Hidden when stderr is not a terminal, so that logs
//! and pipes get no control characters.

use std::io::IsTerminal;
use std::time::Duration;

use fem_core::press::Progress;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

/// Bar positions per run (the bar counts per mille of the simulated time).
const LENGTH: u64 = 1000;

/// A progress bar fed by the engine's per-step callback.
pub struct SimulationBar {
    bar: ProgressBar,
}

impl SimulationBar {
    /// A bar for a run that ends at `end_s` [s].
    pub fn new(end_s: f64) -> Self {
        let target =
            if std::io::stderr().is_terminal() { ProgressDrawTarget::stderr() } else { ProgressDrawTarget::hidden() };
        let bar = ProgressBar::with_draw_target(Some(LENGTH), target);
        let style = ProgressStyle::with_template("{spinner} {elapsed_precise} [{bar:32}] {msg}")
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("=> ");
        bar.set_style(style);
        bar.set_message(format!("t = 0 / {end_s} s, 0 steps"));
        bar.enable_steady_tick(Duration::from_millis(200));
        Self { bar }
    }

    /// Shows the state after a step.
    pub fn update(&self, p: Progress) {
        let fraction = if p.end_s > 0.0 { (p.t_s / p.end_s).clamp(0.0, 1.0) } else { 1.0 };
        self.bar.set_position((fraction * LENGTH as f64).round() as u64);
        self.bar.set_message(format!("t = {:.1} / {} s, {} steps", p.t_s, p.end_s, p.steps));
    }

    /// Removes the bar (the results follow on stdout).
    pub fn finish(&self) {
        self.bar.finish_and_clear();
    }
}
