//! A bounded picture of a streamed history: what `meid simulate -o` draws its pictures from
//! while the history itself streams to `history.csv`.
//!
//! The history of a long run can be far larger than memory; its pictures need only what a
//! screen shows. A [`HistorySketch`] keeps the first [`HEAD_ROWS`] samples whole (the blow and
//! its collision, where every contact force and the bed's acceleration peak, are in them at any
//! usual sample rate) and, after them, the **envelope** of each column: per bucket of
//! consecutive samples its smallest and largest value at their own times, so no excursion
//! between kept points is lost from the picture (a plain every-k-th sample can miss a peak).
//! The picture still shows samples, not the continuous solution: the exact peaks are the
//! summary's, and the pictures' titles quote them.

use crate::io::HISTORY_COLUMNS;

/// Samples kept whole from the start of the run.
pub const HEAD_ROWS: usize = 20_000;
/// Buckets of the envelope after the head (two points per column each).
pub const TAIL_BUCKETS: usize = 2_000;

/// Columns of a history row ([`HISTORY_COLUMNS`]).
const COLUMNS: usize = HISTORY_COLUMNS.len();

/// The head of a history whole and the envelope of its tail (module docs). Fed one row at a
/// time in [`HISTORY_COLUMNS`] order ([`Self::push`]).
#[derive(Debug, Clone)]
pub struct HistorySketch {
    head: Vec<[f64; COLUMNS]>,
    /// Samples per envelope bucket after the head.
    stride: usize,
    /// Per column (time excluded: index 0 unused), the envelope's points `(t, value)`.
    tail: Vec<Vec<(f64, f64)>>,
    /// The open bucket: per column `(t_min, min, t_max, max)`, and its sample count.
    bucket: Vec<(f64, f64, f64, f64)>,
    in_bucket: usize,
    /// Times of the first and the last sample taken.
    span: Option<(f64, f64)>,
}

impl HistorySketch {
    /// A sketch for a history of about `expected_samples` rows (the bucket size follows from
    /// it; more or fewer rows are still taken).
    pub fn new(expected_samples: f64) -> Self {
        let tail_samples = (expected_samples - HEAD_ROWS as f64).max(0.0);
        let stride = (tail_samples / TAIL_BUCKETS as f64).ceil().max(1.0);
        HistorySketch {
            head: Vec::new(),
            stride: if stride.is_finite() && stride < usize::MAX as f64 {
                stride as usize
            } else {
                usize::MAX
            },
            tail: vec![Vec::new(); COLUMNS],
            bucket: vec![(0.0, f64::INFINITY, 0.0, f64::NEG_INFINITY); COLUMNS],
            in_bucket: 0,
            span: None,
        }
    }

    /// Takes one sample, its values in [`HISTORY_COLUMNS`] order.
    pub fn push(&mut self, row: &[f64; COLUMNS]) {
        self.span = Some(self.span.map_or((row[0], row[0]), |(a, _)| (a, row[0])));
        if self.head.len() < HEAD_ROWS {
            self.head.push(*row);
            return;
        }
        let t = row[0];
        for (b, &v) in self.bucket.iter_mut().zip(row).skip(1) {
            // A NaN replaces the extremes, so a non-finite sample shows in the picture.
            if v < b.1 || v.is_nan() {
                b.0 = t;
                b.1 = v;
            }
            if v > b.3 || v.is_nan() {
                b.2 = t;
                b.3 = v;
            }
        }
        self.in_bucket += 1;
        if self.in_bucket >= self.stride {
            self.close_bucket();
        }
    }

    /// Moves the open bucket's extremes into the envelope, in time order.
    fn close_bucket(&mut self) {
        if self.in_bucket == 0 {
            return;
        }
        for (col, b) in self.tail.iter_mut().zip(&mut self.bucket).skip(1) {
            col.extend(extremes(*b));
            *b = (0.0, f64::INFINITY, 0.0, f64::NEG_INFINITY);
        }
        self.in_bucket = 0;
    }

    /// The sketch of column `name` (one of [`HISTORY_COLUMNS`], not `time_s`): the head's
    /// samples, then the tail's envelope, as `(times, values)`; `None` for an unknown name.
    pub fn column(&self, name: &str) -> Option<(Vec<f64>, Vec<f64>)> {
        let c = HISTORY_COLUMNS
            .iter()
            .position(|n| *n == name)
            .filter(|&c| c > 0)?;
        let open = (self.in_bucket > 0).then(|| extremes(self.bucket[c]));
        let points = self
            .head
            .iter()
            .map(|r| (r[0], r[c]))
            .chain(self.tail[c].iter().copied())
            .chain(open.into_iter().flatten());
        Some(points.unzip())
    }

    /// The samples kept whole (the first [`HEAD_ROWS`]).
    pub fn head(&self) -> &[[f64; COLUMNS]] {
        &self.head
    }

    /// The time of the first and of the last sample taken (`None` before any).
    pub fn span(&self) -> Option<(f64, f64)> {
        self.span
    }
}

/// A bucket's `(t_min, min, t_max, max)` as envelope points in time order: its minimum and its
/// maximum, or one point when both are the same sample.
fn extremes((t_lo, lo, t_hi, hi): (f64, f64, f64, f64)) -> impl Iterator<Item = (f64, f64)> {
    let (a, b) = if t_hi < t_lo {
        ((t_hi, hi), (t_lo, lo))
    } else {
        ((t_lo, lo), (t_hi, hi))
    };
    std::iter::once(a).chain((t_lo != t_hi).then_some(b))
}

/// The end of the blow's collision in sampled histories (times `t`, the slider-bed and the
/// bed-damper contact forces), as the summary defines it on the continuous solution: the first
/// sample, after one with a slider-bed contact force, at which both contact forces are zero;
/// `None` if the slider never touches or the collision does not end within the samples.
pub fn collision_end(t: &[f64], slider_bed: &[f64], bed_damper: &[f64]) -> Option<f64> {
    let first = slider_bed.iter().position(|f| *f != 0.0)?;
    (first..t.len())
        .find(|&i| slider_bed[i] == 0.0 && bed_damper.get(i).is_none_or(|f| *f == 0.0))
        .map(|i| t[i])
}

/// [`collision_end`] of rows in [`HISTORY_COLUMNS`] order.
pub fn collision_end_of_rows(rows: &[[f64; COLUMNS]]) -> Option<f64> {
    let col = |name: &str| HISTORY_COLUMNS.iter().position(|n| *n == name);
    let (s, d) = (
        col("contact_force_slider_bed_n")?,
        col("contact_force_bed_damper_n")?,
    );
    let pick = |c: usize| rows.iter().map(|r| r[c]).collect::<Vec<f64>>();
    collision_end(&pick(0), &pick(s), &pick(d))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(t: f64, v: f64) -> [f64; COLUMNS] {
        let mut r = [0.0; COLUMNS];
        r[0] = t;
        r[3] = v;
        r
    }

    #[test]
    fn short_histories_are_kept_whole() {
        let mut s = HistorySketch::new(101.0);
        for i in 0..101 {
            s.push(&row(i as f64, (i as f64).sin()));
        }
        let (t, v) = s.column("bed_acceleration_m_per_s2").unwrap();
        assert_eq!(t.len(), 101);
        assert_eq!(v[7], 7.0_f64.sin());
        assert!(s.column("time_s").is_none() && s.column("nope").is_none());
        assert_eq!(s.span(), Some((0.0, 100.0)));
    }

    #[test]
    fn the_envelope_keeps_every_excursion_of_the_tail() {
        // One spike per 1000 samples, between zeros: an every-k-th sample at k = 1000 would
        // miss all but possibly one of them; the envelope keeps each, at its own time.
        let n = HEAD_ROWS + 1_000_000;
        let mut s = HistorySketch::new(n as f64);
        for i in 0..n {
            let spike = i >= HEAD_ROWS && (i - HEAD_ROWS) % 1000 == 537;
            s.push(&row(i as f64, if spike { -(i as f64) } else { 0.0 }));
        }
        let (t, v) = s.column("bed_acceleration_m_per_s2").unwrap();
        assert!(t.len() <= HEAD_ROWS + 2 * TAIL_BUCKETS + 2);
        let spikes: Vec<(f64, f64)> = t
            .iter()
            .zip(&v)
            .filter(|p| *p.1 != 0.0)
            .map(|(a, b)| (*a, *b))
            .collect();
        assert_eq!(spikes.len(), 1000);
        assert!(spikes.iter().all(|(t, v)| *v == -t));
        assert!(t.windows(2).all(|w| w[0] < w[1]), "time order kept");
        assert_eq!(s.span(), Some((0.0, (n - 1) as f64)));
    }

    #[test]
    fn the_collision_ends_when_both_contacts_are_open() {
        let mut rows = Vec::new();
        for i in 0..100 {
            let mut r = [0.0; COLUMNS];
            r[0] = i as f64;
            r[5] = if (2..10).contains(&i) { 1.0 } else { 0.0 };
            r[6] = if (5..30).contains(&i) || i == 80 {
                1.0
            } else {
                0.0
            };
            rows.push(r);
        }
        assert_eq!(collision_end_of_rows(&rows), Some(30.0));
        assert_eq!(collision_end_of_rows(&rows[..20]), None, "not ended");
        assert_eq!(collision_end_of_rows(&rows[30..]), None, "no blow");
    }
}
