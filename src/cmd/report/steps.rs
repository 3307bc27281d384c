//! The report's progress lines and section times.

use std::io::Write;
use std::time::{Duration, Instant};

use crate::error::Error;

/// Progress lines, `[   12.3 s] what`, timed from the start of the run,
/// and the wall time of each section of the report.
pub struct Steps<'a> {
    start: Instant,
    out: &'a mut dyn Write,
    /// The sections so far: name, start and (once the next began) time.
    sections: Vec<(String, Instant, Option<Duration>)>,
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
        self.sections.push((name.into(), Instant::now(), None));
    }

    /// Stop the running section, if any.
    fn close(&mut self) {
        if let Some((_, t, time @ None)) = self.sections.last_mut() {
            *time = Some(t.elapsed());
        }
    }

    /// Each section's name and wall time, in order.
    pub fn times(&mut self) -> Vec<(String, Duration)> {
        self.close();
        self.sections
            .iter()
            .map(|(name, _, time)| (name.clone(), time.unwrap_or_default()))
            .collect()
    }

    /// Announce the next step.
    pub fn say(&mut self, text: &str) -> Result<(), Error> {
        let t = self.start.elapsed().as_secs_f64();
        writeln!(self.out, "[{t:7.1} s] {text}")?;
        Ok(())
    }
}
