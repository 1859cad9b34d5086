//! The progress display of `demcon run`: one line on stderr that follows the stages — a bar
//! for the packing (φ) and the transient (steps), a spinner with the elapsed time for the
//! others — and, as each stage ends, a line with its wall time and memory.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

use demcon_core::{StageObserver, StageRecord};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

/// The display of one run (hidden with `--quiet`).
#[derive(Clone)]
pub struct RunDisplay {
    bar: ProgressBar,
    /// Whether the stage lines are wanted (not `--quiet`); they go to stderr as plain lines
    /// when the bar cannot be drawn (stderr is not a terminal, e.g. a log file).
    lines: bool,
    /// Whether the bar shows the transient's steps (set at the transient's first report).
    transient: Arc<AtomicBool>,
}

fn style(template: &str) -> ProgressStyle {
    ProgressStyle::with_template(template)
        .expect("static template")
        .progress_chars("=> ")
}

impl RunDisplay {
    /// A display on stderr, or a hidden one.
    pub fn new(visible: bool) -> Self {
        let bar = ProgressBar::with_draw_target(
            Some(0),
            if visible {
                ProgressDrawTarget::stderr()
            } else {
                ProgressDrawTarget::hidden()
            },
        );
        bar.enable_steady_tick(Duration::from_millis(200));
        Self {
            bar,
            lines: visible,
            transient: Arc::new(AtomicBool::new(false)),
        }
    }

    /// Packing progress: φ reached against the target.
    pub fn packing(&self, p: &demcon_packing::PackProgress) {
        self.bar
            .set_position((1000.0 * p.phi / p.target_phi).round() as u64);
        self.bar.set_message(format!("{:.4}", p.phi));
    }

    /// Transient progress: steps done of the total.
    pub fn transient(&self, done: u64, total: u64) {
        if !self.transient.swap(true, Ordering::Relaxed) {
            self.bar.set_style(style(
                "{spinner} transient {bar:30} {pos}/{len} steps [{elapsed}, ETA {eta}]",
            ));
        }
        self.bar.set_length(total);
        self.bar.set_position(done);
    }

    /// Removes the line.
    pub fn finish(&self) {
        self.bar.finish_and_clear();
    }
}

impl StageObserver for RunDisplay {
    fn started(&self, stage: &'static str) {
        self.transient.store(false, Ordering::Relaxed);
        self.bar.reset();
        if stage == "packing" {
            self.bar.set_length(1000);
            self.bar
                .set_style(style("{spinner} packing {bar:30} φ {msg} [{elapsed}]"));
            self.bar.set_message("");
        } else {
            self.bar.set_style(style("{spinner} {msg} [{elapsed}]"));
            self.bar.set_message(stage);
        }
    }

    fn finished(&self, r: &StageRecord) {
        let gb = |b: Option<u64>| b.map_or("–".into(), |b| format!("{:.2} GB", b as f64 / 1e9));
        let line = format!(
            "  {:<14} {:>9.2} s   memory {} (peak {})",
            r.stage,
            r.wall_s,
            gb(r.rss_bytes),
            gb(r.peak_rss_bytes)
        );
        if !self.lines {
            return;
        }
        if self.bar.is_hidden() {
            eprintln!("{line}");
        } else {
            self.bar.println(line);
        }
    }
}
