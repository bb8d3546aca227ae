//! Probe time series, kept in memory and written as CSV (atomically) at each output step.

use super::atomic::write_atomic;
use super::OutputError;
use std::fmt::Write as _;
use std::path::Path;

/// One probe's recorded series.
#[derive(Debug, Clone)]
pub struct Series {
    /// Probe name.
    pub name: String,
    /// Column names after `step,time_s`.
    pub columns: Vec<&'static str>,
    /// Steps of the samples.
    pub steps: Vec<u64>,
    /// Times (s).
    pub times: Vec<f64>,
    /// Rows of values, one per sample, `columns.len()` each.
    pub values: Vec<f64>,
}

impl Series {
    /// Empty series with the given value columns.
    pub fn new(name: &str, columns: Vec<&'static str>) -> Self {
        Self {
            name: name.into(),
            columns,
            steps: Vec::new(),
            times: Vec::new(),
            values: Vec::new(),
        }
    }
    /// Append a sample. Precondition: `v.len() == columns.len()`.
    pub fn push(&mut self, step: u64, time: f64, v: &[f64]) {
        debug_assert_eq!(v.len(), self.columns.len());
        self.steps.push(step);
        self.times.push(time);
        self.values.extend_from_slice(v);
    }
    /// Number of samples.
    pub fn len(&self) -> usize {
        self.steps.len()
    }
    /// True when nothing was recorded.
    pub fn is_empty(&self) -> bool {
        self.steps.is_empty()
    }
    /// Column `c` as a vector.
    pub fn column(&self, c: usize) -> Vec<f64> {
        let n = self.columns.len();
        (0..self.len()).map(|r| self.values[r * n + c]).collect()
    }
    /// Index of a named column.
    pub fn column_index(&self, name: &str) -> Option<usize> {
        self.columns.iter().position(|c| *c == name)
    }
    /// Write `dir/probe_<name>.csv`.
    pub fn write_csv(&self, dir: &Path) -> Result<(), OutputError> {
        let mut s = String::from("step,time_s");
        for c in &self.columns {
            s.push(',');
            s.push_str(c);
        }
        s.push('\n');
        let n = self.columns.len();
        for r in 0..self.len() {
            let _ = write!(s, "{},{:.9e}", self.steps[r], self.times[r]);
            for v in &self.values[r * n..(r + 1) * n] {
                let _ = write!(s, ",{v:.9e}");
            }
            s.push('\n');
        }
        write_atomic(&dir.join(format!("probe_{}.csv", self.name)), s.as_bytes())
    }
}
