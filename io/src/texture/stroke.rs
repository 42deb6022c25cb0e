//! Strokes of the tool: [`find_stroke`] splits the displacement from first touch
//! into compressions (a double compression has two).
//!
//! On the displacement `d` (downward from first touch, mm), with a hysteresis
//! `h` (5 % of the largest displacement after touch) and a return tolerance
//! `r` (the waypoint tolerance), a stroke starting at sample `s`:
//!
//! 1. **pushes**: `d` rises more than `h` above its lowest value since `s` (no
//!    such rise: there is no stroke from `s`);
//! 2. **peaks**: its peak is the largest `d` before `d` falls more than `h`
//!    below it (the tool turns back up);
//! 3. **ends** at the first sample after the peak where the tool is back at its
//!    first-touch position (`d <= r`), or, if it turns down again first (`d`
//!    rises more than `h` above its lowest value since the peak), at that
//!    lowest value; otherwise at the file's end.
//!
//! The next stroke starts where the previous one ends.

/// How a stroke ends.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StrokeEnd {
    /// The tool came back to its first-touch position.
    Returned,
    /// The tool turned down again before reaching it (the stroke ends at its highest point).
    TurnedBack,
    /// The file ended first.
    FileEnd,
}

impl StrokeEnd {
    /// How the end is described in a bundle's `[extra]`.
    pub fn as_str(self) -> &'static str {
        match self {
            StrokeEnd::Returned => "tool back at the first-touch position",
            StrokeEnd::TurnedBack => "tool turned down again",
            StrokeEnd::FileEnd => "end of the file",
        }
    }
}

/// One compression of the tool; indices into the displacement slice.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Stroke {
    /// The first sample of the stroke's window.
    pub start: usize,
    /// The sample of the largest displacement.
    pub peak: usize,
    /// The last sample of the stroke's window.
    pub end: usize,
    /// How the window ends.
    pub end_rule: StrokeEnd,
}

/// The stroke starting at sample `start` of `d`, if the tool pushes after it (see
/// the module docs). `hysteresis` and `returned` are in the unit of `d`.
pub fn find_stroke(d: &[f64], start: usize, hysteresis: f64, returned: f64) -> Option<Stroke> {
    let n = d.len();
    if start >= n {
        return None;
    }
    // 1. The push.
    let mut low = d[start];
    let push = (start..n).find(|&j| {
        low = low.min(d[j]);
        d[j] > low + hysteresis
    })?;
    // 2. The peak.
    let mut peak = push;
    let mut turned = false;
    for k in push..n {
        if d[k] > d[peak] {
            peak = k;
        } else if d[k] < d[peak] - hysteresis {
            turned = true;
            break;
        }
    }
    if !turned {
        return Some(Stroke { start, peak, end: n - 1, end_rule: StrokeEnd::FileEnd });
    }
    // 3. The end of the unloading.
    let mut lowest = peak;
    for l in peak..n {
        if d[l] <= returned {
            return Some(Stroke { start, peak, end: l, end_rule: StrokeEnd::Returned });
        }
        if d[l] < d[lowest] {
            lowest = l;
        } else if d[l] > d[lowest] + hysteresis {
            return Some(Stroke { start, peak, end: lowest, end_rule: StrokeEnd::TurnedBack });
        }
    }
    Some(Stroke { start, peak, end: n - 1, end_rule: StrokeEnd::FileEnd })
}

/// The loading speed [unit of `d` per unit of `t`] of the samples `range`: the
/// least-squares slope of `d` over `t` through the samples whose `d` lies between
/// 10 % and 90 % of `top` (the ramp without its start and turn). `None` with
/// fewer than two such samples.
pub fn ramp_speed(t: &[f64], d: &[f64], range: std::ops::Range<usize>, top: f64) -> Option<f64> {
    let (lo, hi) = (0.1 * top, 0.9 * top);
    let pts: Vec<(f64, f64)> = range.filter(|&i| d[i] >= lo && d[i] <= hi).map(|i| (t[i], d[i])).collect();
    if pts.len() < 2 {
        return None;
    }
    let m = pts.len() as f64;
    let (mt, md) = (pts.iter().map(|p| p.0).sum::<f64>() / m, pts.iter().map(|p| p.1).sum::<f64>() / m);
    let stt: f64 = pts.iter().map(|p| (p.0 - mt).powi(2)).sum();
    let std: f64 = pts.iter().map(|p| (p.0 - mt) * (p.1 - md)).sum();
    (stt > 0.0).then(|| std / stt).filter(|v| v.is_finite())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// d(t) of a double compression: down 0.2 mm/s to 4 mm, up to 0.3 mm above touch,
    /// rest, down to 3.8 mm, up; sampled every 0.01 s.
    fn double() -> (Vec<f64>, Vec<f64>) {
        let legs = [(0.0, 0.0), (20.0, 4.0), (41.5, -0.3), (45.0, -0.3), (65.5, 3.8), (86.0, -0.3), (100.0, -0.3)];
        let t: Vec<f64> = (0..=10_000).map(|i| i as f64 * 0.01).collect();
        let d = t
            .iter()
            .map(|&x| {
                let w = legs.windows(2).find(|w| x <= w[1].0).unwrap_or(&legs[legs.len() - 2..]);
                let ((t0, d0), (t1, d1)) = (w[0], w[1]);
                d0 + (d1 - d0) * (x - t0) / (t1 - t0)
            })
            .collect();
        (t, d)
    }

    #[test]
    fn splits_a_double_compression() {
        let (t, d) = double();
        let s1 = find_stroke(&d, 0, 0.2, 0.001).unwrap();
        assert_eq!((s1.start, s1.peak, s1.end_rule), (0, 2000, StrokeEnd::Returned));
        assert!((t[s1.end] - 40.0).abs() < 0.02, "{}", t[s1.end]);
        let s2 = find_stroke(&d, s1.end, 0.2, 0.001).unwrap();
        assert_eq!(s2.peak, 6550);
        assert!((t[s2.end] - 84.5).abs() < 0.02 && s2.end_rule == StrokeEnd::Returned, "{}", t[s2.end]);
        assert_eq!(find_stroke(&d, s2.end, 0.2, 0.001), None);
        let v = ramp_speed(&t, &d, 0..s1.peak, d[s1.peak]).unwrap();
        assert!((v - 0.2).abs() < 1e-9, "{v}");
    }

    #[test]
    fn a_tool_that_turns_before_returning_ends_at_its_highest_point() {
        let (_, d) = double();
        // Returning means d <= -1 here: never; the stroke ends where the tool is highest.
        let s1 = find_stroke(&d, 0, 0.2, -1.0).unwrap();
        assert_eq!(s1.end_rule, StrokeEnd::TurnedBack);
        assert!((d[s1.end] + 0.3).abs() < 1e-12);
    }

    #[test]
    fn a_push_and_hold_ends_at_the_file_end() {
        let d: Vec<f64> = (0..100).map(|i| (i as f64 * 0.1).min(5.0)).collect();
        let s = find_stroke(&d, 0, 0.25, 0.001).unwrap();
        assert_eq!((s.peak, s.end, s.end_rule), (50, 99, StrokeEnd::FileEnd));
        assert_eq!(find_stroke(&[0.0; 10], 0, 0.1, 0.0), None);
        assert_eq!(find_stroke(&d, 100, 0.1, 0.0), None);
    }
}
