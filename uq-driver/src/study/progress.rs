//! Progress of a run: a bar on a terminal, and plain lines when the output goes to a file or
//! a pipe (a cluster job's log): one line every `interval` (default 10 s), or whenever
//! another tenth of the points is done once the run has taken a second, and one at the end
//! (a run shorter than a second prints none).

use std::io::Write;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Mutex, RwLock};
use std::time::{Duration, Instant};

/// Where the library's messages to the user go (notes and warnings printed as a study runs:
/// "taking over a stale lock", "N points failed in an earlier run", a variant starting, …).
pub type Sink = Box<dyn Fn(&str) + Send + Sync>;
static MESSAGES: RwLock<Option<Sink>> = RwLock::new(None);

/// Sends the library's messages to `sink` (None: nowhere, the default). The command line
/// prints them on stderr (`print_messages`); a host can log them, show them or drop them.
/// Warnings that matter for the results are in `summary.warnings` as well.
pub fn set_message_sink(sink: Option<Sink>) {
    *MESSAGES.write().unwrap_or_else(|e| e.into_inner()) = sink;
}

/// Sends the library's messages to stderr, one line each (the command line's choice).
pub fn print_messages() {
    set_message_sink(Some(Box::new(|line| eprintln!("{line}"))));
}

/// One message for the user, to the sink of [`set_message_sink`] (nowhere by default).
pub fn message(line: &str) {
    if let Some(sink) = MESSAGES.read().unwrap_or_else(|e| e.into_inner()).as_ref() {
        sink(line);
    }
}

/// How progress is shown.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ProgressMode {
    /// Not at all.
    #[default]
    Off,
    /// A bar that redraws itself (a terminal).
    Bar,
    /// A line now and then (a log file).
    Lines,
}

/// Progress over `total` points.
pub struct Progress {
    bar: Option<indicatif::ProgressBar>,
    lines: Option<Lines>,
}

struct Lines {
    total: usize,
    done: AtomicUsize,
    started: Instant,
    interval: Duration,
    /// When the last line was printed, the tenth it reported, and whether any was.
    last: Mutex<(Instant, usize, bool)>,
}

/// Lines about tenths start once the run has taken this long.
const QUIET: Duration = Duration::from_secs(1);

impl Progress {
    /// Progress shown as `mode` (nothing for no points).
    pub fn new(mode: ProgressMode, total: usize) -> Progress {
        Progress::with_interval(mode, total, Duration::from_secs(10))
    }

    /// As [`Progress::new`], with lines at most `interval` apart.
    pub fn with_interval(mode: ProgressMode, total: usize, interval: Duration) -> Progress {
        let (mut bar, mut lines) = (None, None);
        if total > 0 {
            match mode {
                ProgressMode::Off => {}
                ProgressMode::Bar => {
                    let b = indicatif::ProgressBar::new(total as u64);
                    b.set_style(
                        indicatif::ProgressStyle::with_template(
                            "{bar:40} {pos}/{len} points  {elapsed} elapsed, ~{eta} left",
                        )
                        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
                    );
                    bar = Some(b);
                }
                ProgressMode::Lines => {
                    let now = Instant::now();
                    lines = Some(Lines {
                        total,
                        done: AtomicUsize::new(0),
                        started: now,
                        interval,
                        last: Mutex::new((now, 0, false)),
                    });
                }
            }
        }
        Progress { bar, lines }
    }

    /// One more point done.
    pub fn inc(&self) {
        if let Some(b) = &self.bar {
            b.inc(1);
        }
        if let Some(l) = &self.lines {
            let done = l.done.fetch_add(1, Ordering::Relaxed) + 1;
            let tenth = done * 10 / l.total;
            let mut last = l.last.lock().unwrap_or_else(|e| e.into_inner());
            let due =
                (tenth > last.1 && l.started.elapsed() >= QUIET) || last.0.elapsed() >= l.interval;
            if done < l.total && due {
                *last = (Instant::now(), tenth, true);
                l.print(done);
            }
        }
    }

    /// Prints a line on stderr without garbling the bar (a bar is drawn on the command
    /// line's terminal only); without a bar the line is a message to the sink of
    /// [`set_message_sink`], as every other note of the library.
    pub fn println(&self, line: &str) {
        match &self.bar {
            Some(b) => b.suspend(|| eprintln!("{line}")),
            None => message(line),
        }
    }

    /// The run is over (a last line with the count).
    pub fn finish(&self) {
        if let Some(b) = &self.bar {
            b.finish_and_clear();
        }
        if let Some(l) = &self.lines {
            let printed = l.last.lock().unwrap_or_else(|e| e.into_inner()).2;
            if printed || l.started.elapsed() >= QUIET {
                l.print(l.done.load(Ordering::Relaxed));
            }
        }
    }
}

impl Lines {
    fn print(&self, done: usize) {
        let elapsed = self.started.elapsed().as_secs_f64();
        let left = if done > 0 && done < self.total {
            format!(
                ", ~{:.0} s left",
                elapsed * (self.total - done) as f64 / done as f64
            )
        } else {
            String::new()
        };
        let _ = writeln!(
            std::io::stderr().lock(),
            "uq-driver: {done}/{} points ({:.0} %), {elapsed:.1} s elapsed{left}",
            self.total,
            100.0 * done as f64 / self.total as f64
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lines_come_at_tenths_after_a_second_and_count_every_point() {
        let p = Progress::with_interval(ProgressMode::Lines, 95, Duration::from_secs(3600));
        for _ in 0..50 {
            p.inc();
        }
        let l = p.lines.as_ref().unwrap();
        assert!(
            !l.last.lock().unwrap().2,
            "nothing printed in the first second"
        );
        std::thread::sleep(QUIET);
        for _ in 50..95 {
            p.inc();
        }
        assert_eq!(l.done.load(Ordering::Relaxed), 95);
        assert_eq!(
            l.last.lock().unwrap().1,
            9,
            "the last tenth printed before the end"
        );
        p.finish();
        assert!(Progress::new(ProgressMode::Lines, 0).lines.is_none());
        assert!(Progress::new(ProgressMode::Off, 10).lines.is_none());
    }

    /// Library code printed notes to stderr unasked; they now go to the sink a
    /// host sets (the CLI: stderr), nowhere by default.
    #[test]
    fn library_messages_go_to_the_sink_that_is_set_and_nowhere_by_default() {
        use std::sync::Arc;
        message("dropped: no sink yet");
        let got = Arc::new(Mutex::new(Vec::<String>::new()));
        let g = Arc::clone(&got);
        set_message_sink(Some(Box::new(move |l| {
            g.lock().unwrap().push(l.to_owned())
        })));
        message("a note");
        set_message_sink(None);
        message("dropped again");
        assert_eq!(*got.lock().unwrap(), vec!["a note".to_owned()]);
    }
}
