//! The report's progress lines and section times.

use std::io::Write;
use std::time::{Duration, Instant};

use crate::error::Error;
use crate::machine::cpu_time;

/// Progress lines, `[   12.3 s] what`, timed from the start of the run,
/// and the wall and CPU time of each section of the report.
pub struct Steps<'a> {
    start: Instant,
    out: &'a mut dyn Write,
    /// The sections so far.
    sections: Vec<Section>,
}

/// One section: its name, when it began (wall clock and the process's CPU
/// time), and once the next began, its times.
struct Section {
    name: String,
    start: Instant,
    cpu_start: Option<Duration>,
    times: Option<SectionTime>,
}

/// How long a section took.
#[derive(Debug, Clone, Copy, Default)]
pub struct SectionTime {
    /// Wall time.
    pub wall: Duration,
    /// CPU time of every thread, user and system (`None` if the system
    /// does not say).
    pub cpu: Option<Duration>,
}

impl<'a> Steps<'a> {
    /// Lines to `out`, timed from `start`.
    pub fn new(start: Instant, out: &'a mut dyn Write) -> Steps<'a> {
        Steps {
            start,
            out,
            sections: Vec::new(),
        }
    }

    /// Start timing the next section (and stop the one before).
    pub fn section(&mut self, name: impl Into<String>) {
        self.close();
        self.sections.push(Section {
            name: name.into(),
            start: Instant::now(),
            cpu_start: cpu_time(),
            times: None,
        });
    }

    /// Stop the running section, if any.
    fn close(&mut self) {
        if let Some(s @ Section { times: None, .. }) = self.sections.last_mut() {
            s.times = Some(SectionTime {
                wall: s.start.elapsed(),
                cpu: s
                    .cpu_start
                    .zip(cpu_time())
                    .map(|(a, b)| b.saturating_sub(a)),
            });
        }
    }

    /// Each section's name and times, in order.
    pub fn times(&mut self) -> Vec<(String, SectionTime)> {
        self.close();
        self.sections
            .iter()
            .map(|s| (s.name.clone(), s.times.unwrap_or_default()))
            .collect()
    }

    /// Announce the next step.
    pub fn say(&mut self, text: &str) -> Result<(), Error> {
        let t = self.start.elapsed().as_secs_f64();
        writeln!(self.out, "[{t:7.1} s] {text}")?;
        Ok(())
    }
}
