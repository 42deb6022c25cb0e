//! The colour scale of displacement magnitude: viridis.

/// The colormap's name, as written in the file's extras.
pub const COLORMAP: &str = "viridis";

/// Viridis (van der Walt and Smith, matplotlib's default) at nine evenly spaced
/// points from 0 to 1, sRGB `0..=255` (the `viridisLite::viridis(9)` palette).
const VIRIDIS_SRGB: [[u8; 3]; 9] = [
    [0x44, 0x01, 0x54],
    [0x47, 0x2d, 0x7b],
    [0x3b, 0x52, 0x8b],
    [0x2c, 0x72, 0x8e],
    [0x21, 0x90, 0x8c],
    [0x27, 0xad, 0x81],
    [0x5d, 0xc8, 0x63],
    [0xaa, 0xdc, 0x32],
    [0xfd, 0xe7, 0x25],
];

/// sRGB-encoded `c` in `[0, 1]` to linear light (IEC 61966-2-1).
fn srgb_to_linear(c: f64) -> f64 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// The colour of `s` in `[0, 1]` (clamped; NaN counts as 0) as **linear** RGB in
/// `[0, 1]`, which is what glTF's `COLOR_0` holds: interpolated in sRGB between
/// the nine control points, then linearized.
pub fn viridis_linear(s: f64) -> [f64; 3] {
    let s = if s.is_nan() { 0.0 } else { s.clamp(0.0, 1.0) };
    let x = s * (VIRIDIS_SRGB.len() - 1) as f64;
    let i = (x.floor() as usize).min(VIRIDIS_SRGB.len() - 2);
    let w = x - i as f64;
    let (a, b) = (VIRIDIS_SRGB[i], VIRIDIS_SRGB[i + 1]);
    std::array::from_fn(|k| {
        let srgb = (f64::from(a[k]) * (1.0 - w) + f64::from(b[k]) * w) / 255.0;
        srgb_to_linear(srgb).clamp(0.0, 1.0)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ends_are_dark_purple_and_yellow_and_the_luminance_rises() {
        let lum = |c: [f64; 3]| 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2];
        let lo = viridis_linear(0.0);
        let hi = viridis_linear(1.0);
        assert!(lo[2] > lo[0] && lo[2] > lo[1], "{lo:?}");
        assert!(hi[0] > 0.9 && hi[1] > 0.75 && hi[2] < 0.05, "{hi:?}");
        let mut previous = -1.0;
        for i in 0..=100 {
            let c = viridis_linear(f64::from(i) / 100.0);
            assert!(c.iter().all(|x| (0.0..=1.0).contains(x)));
            assert!(lum(c) > previous, "luminance rises monotonically (perceptual order) at {i}");
            previous = lum(c);
        }
        assert_eq!(viridis_linear(-3.0), lo);
        assert_eq!(viridis_linear(f64::NAN), lo);
        assert_eq!(viridis_linear(7.0), hi);
    }

    #[test]
    fn srgb_round_numbers() {
        assert_eq!(srgb_to_linear(0.0), 0.0);
        assert!((srgb_to_linear(1.0) - 1.0).abs() < 1e-12);
        assert!((srgb_to_linear(0.5) - 0.214_041).abs() < 1e-6);
    }
}
