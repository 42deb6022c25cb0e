//! First touch, tare and noise: [`detect_touch`].
//!
//! The rule, on the force samples `f[i]` of the whole file:
//!
//! 0. **A rise at all?** The largest force must exceed the median of the first
//!    16 samples by more than 5 noise sigmas, the noise estimated from the whole
//!    file's first differences (1.4826 x their MAD / sqrt 2; a smooth contact
//!    curve hardly changes them). Otherwise: no contact.
//! 1. **Leading window.** `P` is the largest force and `h` the first sample at
//!    which the force has risen half-way from the median of the first 16 samples
//!    to `P`. The leading window is the first 2 % of the samples before `h`
//!    (at least 16, at most half of them): samples before the force rises.
//! 2. **Pass 1.** From the leading window, a level `b` (median) and a noise
//!    `sigma` (1.4826 x the median absolute deviation: the standard deviation
//!    of Gaussian noise, unmoved by spikes or the start of a rise). The
//!    threshold is `theta = max(5 sigma, 1 % of (P - b))`. The crossing `c` is
//!    the first sample from which the force stays above `b + theta` up to `h`
//!    (a lone spike before contact does not count), and it must stay above for
//!    at least 10 rows (a spike alone is no contact). First touch is refined
//!    back from `c` to the last sample still inside the noise band,
//!    `f <= b + 2 sigma`: where the force leaves the noise.
//! 3. **Pass 2.** The pre-contact segment is every sample up to that touch.
//!    The **tare** is its mean, the **noise** `sigma` its 1.4826 x MAD, and step
//!    2's threshold, crossing and refinement are repeated with them: the touch
//!    reported is this pass's. The leading window only serves to find the
//!    segment; the longer segment gives a better tare.
//!
//! Refused as "no contact found": a force that never rises above the pre-contact
//! level by more than `theta`, or that is above the noise band from the first
//! samples on (no pre-contact segment to tare with; the file must start before
//! the tool touches). On the step from noise to a linear rise of slope `s` the
//! touch found lies within about `5 sigma / s` of the true one (the refinement
//! stops where the rise reaches the band, about `2 sigma / s` late, give or take
//! the noise).
//!
//! A slow drift before contact (the Exponent's probe entering liquid, say) lifts
//! the segment's mean and `sigma` a little; it is not removed.

/// Robust noise: this many median absolute deviations make one standard deviation.
pub const MAD_TO_SIGMA: f64 = 1.4826;
/// The leading window is this fraction of the samples before the force's half rise.
pub const LEADING_FRACTION: f64 = 0.02;
/// The leading window holds at least this many samples.
pub const MIN_LEADING_SAMPLES: usize = 16;
/// Fewer samples than this before the rise: no pre-contact segment.
pub const MIN_PRE_CONTACT_SAMPLES: usize = 8;
/// The contact threshold is at least this many noise sigmas ...
pub const THRESHOLD_SIGMAS: f64 = 5.0;
/// ... and at least this fraction of the peak force above the pre-contact level.
pub const THRESHOLD_PEAK_FRACTION: f64 = 0.01;
/// The noise band: this many sigmas above the tare.
pub const BAND_SIGMAS: f64 = 2.0;
/// A contact keeps the force above the threshold for at least this many rows.
pub const MIN_CONTACT_ROWS: usize = 10;

/// What [`detect_touch`] found. Indices are into the force slice it was given.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TouchDetection {
    /// The first-touch sample: the last one inside the noise band before the rise.
    pub touch: usize,
    /// The first sample of the rise above the threshold.
    pub crossing: usize,
    /// The sample of the largest force.
    pub peak: usize,
    /// The mean force of the pre-contact segment [force unit of the input].
    pub tare: f64,
    /// The noise of the pre-contact segment (1.4826 x MAD).
    pub sigma: f64,
    /// The contact threshold above the tare: max(5 sigma, 1 % of the peak above the tare).
    pub threshold: f64,
    /// The half-width of the noise band above the tare: 2 sigma.
    pub band: f64,
    /// The number of samples in the pre-contact segment.
    pub pre_contact: usize,
}

/// Why no touch was found (the caller adds the file and line).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum NoTouch {
    /// Too few samples to tell noise from contact.
    TooShort {
        /// The number of samples.
        samples: usize,
        /// The number needed.
        needed: usize,
    },
    /// The force never rises more than `threshold` above `level` for
    /// [`MIN_CONTACT_ROWS`] rows.
    NoRise {
        /// The sample of the largest force.
        peak: usize,
        /// The pre-contact level.
        level: f64,
        /// The threshold above it.
        threshold: f64,
    },
    /// The force is above the noise from the first samples on.
    NoPreContact {
        /// The sample where the rise was found.
        crossing: usize,
    },
}

/// The median of `x` (not empty); NaN-free input assumed (the readers refuse NaN).
pub(crate) fn median(x: &[f64]) -> f64 {
    let mut v = x.to_vec();
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n == 0 {
        return 0.0;
    }
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// (median, 1.4826 x median absolute deviation) of `x`.
pub(crate) fn robust_level_and_sigma(x: &[f64]) -> (f64, f64) {
    let m = median(x);
    let dev: Vec<f64> = x.iter().map(|v| (v - m).abs()).collect();
    (m, MAD_TO_SIGMA * median(&dev))
}

fn mean(x: &[f64]) -> f64 {
    if x.is_empty() {
        0.0
    } else {
        x.iter().sum::<f64>() / x.len() as f64
    }
}

/// The index of the first largest value of `x[range]`.
pub(crate) fn argmax(x: &[f64], range: std::ops::Range<usize>) -> usize {
    let mut best = range.start;
    for i in range {
        if x[i] > x[best] {
            best = i;
        }
    }
    best
}

/// A rise above `level` within `range` (of `f`): `(touch, crossing, peak, threshold, band)`.
/// Uses `sigma` for the threshold and band; see the module docs.
pub(crate) fn locate_rise(
    f: &[f64],
    range: std::ops::Range<usize>,
    level: f64,
    sigma: f64,
) -> Result<(usize, usize, usize, f64, f64), NoTouch> {
    let start = range.start;
    let peak = argmax(f, range.clone());
    let rise = f[peak] - level;
    let threshold = (THRESHOLD_SIGMAS * sigma).max(THRESHOLD_PEAK_FRACTION * rise);
    let rises = rise > threshold; // false for NaN
    if !rises {
        return Err(NoTouch::NoRise { peak, level, threshold });
    }
    let band = BAND_SIGMAS * sigma;
    // h: the first sample at half the rise (the peak itself at worst).
    let half = (start..=peak).find(|&i| f[i] - level >= 0.5 * rise).unwrap_or(peak);
    // The crossing: one past the last sample before h that is not above the threshold.
    let crossing = match (start..half).rev().find(|&j| f[j] - level <= threshold) {
        Some(j) => j + 1,
        None => return Err(NoTouch::NoPreContact { crossing: start }),
    };
    // A contact lasts: a spike above the threshold is not one.
    let lasts = crossing + MIN_CONTACT_ROWS <= range.end
        && f[crossing..crossing + MIN_CONTACT_ROWS].iter().all(|&x| x - level > threshold);
    if !lasts {
        return Err(NoTouch::NoRise { peak, level, threshold });
    }
    // Refine back to the last sample inside the noise band.
    let touch = match (start..crossing).rev().find(|&k| f[k] - level <= band) {
        Some(k) => k,
        None => return Err(NoTouch::NoPreContact { crossing }),
    };
    Ok((touch, crossing, peak, threshold, band))
}

/// Finds the tare, the noise and first touch in `force` (see the module docs).
pub fn detect_touch(force: &[f64]) -> Result<TouchDetection, NoTouch> {
    let n = force.len();
    let needed = 2 * MIN_LEADING_SAMPLES;
    if n < needed {
        return Err(NoTouch::TooShort { samples: n, needed });
    }
    // 0. Is there a rise at all? Against the noise of the whole file, estimated
    // from its first differences (a smooth contact curve hardly moves them).
    let first = median(&force[..MIN_LEADING_SAMPLES]);
    let peak = argmax(force, 0..n);
    let rise = force[peak] - first;
    let diffs: Vec<f64> = force.windows(2).map(|w| w[1] - w[0]).collect();
    let diff_sigma = robust_level_and_sigma(&diffs).1 / std::f64::consts::SQRT_2;
    let significant = THRESHOLD_SIGMAS * diff_sigma;
    let rises = rise > significant; // false for NaN
    if !rises {
        return Err(NoTouch::NoRise { peak, level: first, threshold: significant });
    }
    // 1. The leading window.
    let half = (0..=peak).find(|&i| force[i] - first >= 0.5 * rise).unwrap_or(peak);
    let leading = ((LEADING_FRACTION * half as f64) as usize).max(MIN_LEADING_SAMPLES).min(half / 2);
    if leading < MIN_PRE_CONTACT_SAMPLES {
        return Err(NoTouch::NoPreContact { crossing: half });
    }
    // 2. Pass 1: the pre-contact segment.
    let (level, sigma) = robust_level_and_sigma(&force[..leading]);
    let (touch1, _, _, _, _) = locate_rise(force, 0..n, level, sigma)?;
    // 3. Pass 2: tare and noise from the segment, touch again.
    let pre_contact = touch1 + 1;
    let (tare, sigma) = if pre_contact >= MIN_PRE_CONTACT_SAMPLES {
        let segment = &force[..pre_contact];
        (mean(segment), robust_level_and_sigma(segment).1)
    } else {
        (mean(&force[..leading]), sigma)
    };
    let (touch, crossing, peak, threshold, band) = locate_rise(force, 0..n, tare, sigma)?;
    Ok(TouchDetection { touch, crossing, peak, tare, sigma, threshold, band, pre_contact })
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A small deterministic generator (xorshift64*) for noise in tests.
    pub(crate) struct Rng(pub u64);

    impl Rng {
        pub(crate) fn next_u64(&mut self) -> u64 {
            self.0 ^= self.0 >> 12;
            self.0 ^= self.0 << 25;
            self.0 ^= self.0 >> 27;
            self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
        }
        /// Uniform in (0, 1).
        pub(crate) fn uniform(&mut self) -> f64 {
            ((self.next_u64() >> 11) as f64 + 0.5) / (1u64 << 53) as f64
        }
        /// Standard normal (Box-Muller).
        pub(crate) fn normal(&mut self) -> f64 {
            let (u, v) = (self.uniform(), self.uniform());
            (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
        }
    }

    /// A synthetic force: `tare` + Gaussian noise `sigma`, and from `t0` a linear
    /// rise of `slope` up to `top`, then back down at the same rate.
    pub(crate) struct Ramp {
        pub t0: f64,
        pub slope: f64,
        pub top: f64,
        pub tare: f64,
        pub sigma: f64,
    }

    impl Ramp {
        /// `n` samples every `dt`, noise from `seed`.
        pub(crate) fn sample(&self, n: usize, dt: f64, seed: u64) -> Vec<f64> {
            let mut rng = Rng(seed);
            let t_top = self.t0 + self.top / self.slope;
            (0..n)
                .map(|i| {
                    let t = i as f64 * dt;
                    let clean = if t <= self.t0 {
                        0.0
                    } else if t <= t_top {
                        self.slope * (t - self.t0)
                    } else {
                        (self.top - self.slope * (t - t_top)).max(0.0)
                    };
                    self.tare + clean + self.sigma * rng.normal()
                })
                .collect()
        }
    }

    #[test]
    fn medians_and_mad() {
        assert_eq!(median(&[3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(&[4.0, 1.0, 2.0, 3.0]), 2.5);
        let (m, s) = robust_level_and_sigma(&[1.0, 1.0, 2.0, 3.0, 100.0]);
        assert_eq!((m, s), (2.0, MAD_TO_SIGMA));
    }

    #[test]
    fn finds_tare_noise_and_touch_on_a_noisy_ramp() {
        // 100 Hz, touch at 5 s, 1 N/s to 10 N, tare 0.3 N, noise 0.01 N.
        let (dt, t0, slope, tare, sigma) = (0.01, 5.0, 1.0, 0.3, 0.01);
        for seed in 1..=20u64 {
            let f = Ramp { t0, slope, top: 10.0, tare, sigma }.sample(3000, dt, seed);
            let d = detect_touch(&f).unwrap();
            let t_touch = d.touch as f64 * dt;
            // Stated tolerance: 5 sigma / slope plus one sample.
            assert!((t_touch - t0).abs() <= 5.0 * sigma / slope + dt, "seed {seed}: touch at {t_touch} s");
            // The tare is the mean of ~500 samples: within 4 sigma / sqrt(400).
            assert!((d.tare - tare).abs() <= 4.0 * sigma / 20.0, "seed {seed}: tare {}", d.tare);
            assert!((d.sigma / sigma - 1.0).abs() < 0.2, "seed {seed}: sigma {}", d.sigma);
            assert_eq!(d.threshold, (5.0 * d.sigma).max(0.01 * (f[d.peak] - d.tare)));
            assert!(d.crossing > d.touch && d.pre_contact > 400);
        }
    }

    #[test]
    fn a_spike_before_contact_is_not_a_touch() {
        let mut f = Ramp { t0: 5.0, slope: 1.0, top: 10.0, tare: 0.0, sigma: 0.01 }.sample(3000, 0.01, 7);
        f[200] = 5.0; // one spike at 2 s, half the peak
        let d = detect_touch(&f).unwrap();
        assert!((d.touch as f64 * 0.01 - 5.0).abs() <= 0.06, "{d:?}");
    }

    #[test]
    fn a_spike_alone_is_no_contact() {
        let mut rng = Rng(4);
        let mut f: Vec<f64> = (0..700).map(|_| 0.02 + 0.0015 * rng.normal()).collect();
        f[500] += 0.011;
        f[501] += 0.006;
        assert!(matches!(detect_touch(&f), Err(NoTouch::NoRise { peak: 500, .. })), "{:?}", detect_touch(&f));
    }

    #[test]
    fn noise_alone_is_no_contact() {
        let mut rng = Rng(3);
        let f: Vec<f64> = (0..2000).map(|_| 0.02 + 0.01 * rng.normal()).collect();
        assert!(matches!(detect_touch(&f), Err(NoTouch::NoRise { .. })), "{:?}", detect_touch(&f));
        assert!(matches!(detect_touch(&[1.0; 100]), Err(NoTouch::NoRise { .. })));
        assert!(matches!(detect_touch(&[1.0; 10]), Err(NoTouch::TooShort { samples: 10, .. })));
    }

    #[test]
    fn a_file_that_starts_at_the_peak_has_no_pre_contact_segment() {
        let step: Vec<f64> = (0..1000).map(|i| if i < 10 { 0.0 } else { 1.0 }).collect();
        assert!(matches!(detect_touch(&step), Err(NoTouch::NoPreContact { .. })), "{:?}", detect_touch(&step));
        let f: Vec<f64> = (0..1000).map(|i| 10.0 - i as f64 * 0.01).collect();
        assert!(matches!(detect_touch(&f), Err(NoTouch::NoPreContact { .. })), "{:?}", detect_touch(&f));
    }
}
