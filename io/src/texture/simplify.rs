//! Piecewise-linear simplification of a sampled curve: [`simplify`].
//!
//! Douglas-Peucker with the *vertical* distance (the value's error at the
//! sample's own time, not the perpendicular distance, which would mix seconds
//! and millimetres): the first and last points are kept; on each kept segment the
//! point farthest from the chord is kept when it lies farther than the tolerance,
//! and both halves are treated the same way. Every input point then lies within
//! the tolerance of the polyline through the kept points, at its own time.

/// The indices of the points of `points` (`[t, y]`, `t` strictly increasing) to
/// keep so that every point lies within `tolerance` (in `y`) of the linear
/// interpolation between the kept ones. Always keeps the first and last points;
/// empty for empty input. A tolerance that is not a number > 0 keeps every
/// point that is not on a chord exactly.
pub fn simplify(points: &[[f64; 2]], tolerance: f64) -> Vec<usize> {
    let n = points.len();
    if n <= 2 {
        return (0..n).collect();
    }
    let tolerance = if tolerance > 0.0 { tolerance } else { 0.0 };
    let mut keep = vec![false; n];
    keep[0] = true;
    keep[n - 1] = true;
    // An explicit stack of segments: no recursion depth to worry about.
    let mut stack = vec![(0usize, n - 1)];
    while let Some((a, b)) = stack.pop() {
        if b <= a + 1 {
            continue;
        }
        let ([ta, ya], [tb, yb]) = (points[a], points[b]);
        let mut worst = (a, 0.0f64);
        for (i, p) in points.iter().enumerate().take(b).skip(a + 1) {
            let on_chord = if tb > ta { ya + (yb - ya) * (p[0] - ta) / (tb - ta) } else { ya };
            let e = (p[1] - on_chord).abs();
            if e > worst.1 {
                worst = (i, e);
            }
        }
        if worst.1 > tolerance {
            keep[worst.0] = true;
            stack.push((a, worst.0));
            stack.push((worst.0, b));
        }
    }
    (0..n).filter(|&i| keep[i]).collect()
}

/// The value at `t` of the polyline through `points` (held flat outside them).
pub fn interpolate(points: &[[f64; 2]], t: f64) -> f64 {
    match points {
        [] => 0.0,
        [p] => p[1],
        _ => {
            if t <= points[0][0] {
                return points[0][1];
            }
            for w in points.windows(2) {
                let ([t0, y0], [t1, y1]) = (w[0], w[1]);
                if t <= t1 {
                    return if t1 > t0 { y0 + (y1 - y0) * (t - t0) / (t1 - t0) } else { y1 };
                }
            }
            points[points.len() - 1][1]
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::texture::touch::tests::Rng;

    fn max_error(points: &[[f64; 2]], kept: &[usize]) -> f64 {
        let poly: Vec<[f64; 2]> = kept.iter().map(|&i| points[i]).collect();
        points.iter().map(|p| (p[1] - interpolate(&poly, p[0])).abs()).fold(0.0, f64::max)
    }

    #[test]
    fn a_straight_line_keeps_its_ends_and_a_ramp_its_kinks() {
        let line: Vec<[f64; 2]> = (0..100).map(|i| [i as f64, 0.2 * i as f64]).collect();
        assert_eq!(simplify(&line, 1e-9), vec![0, 99]);
        // Up at 0.2/s for 50 s, hold 20 s, down: kinks at 50 and 70.
        let tri: Vec<[f64; 2]> = (0..=100)
            .map(|i| {
                let t = i as f64;
                [
                    t,
                    if t <= 50.0 {
                        0.2 * t
                    } else if t <= 70.0 {
                        10.0
                    } else {
                        10.0 - 0.2 * (t - 70.0)
                    },
                ]
            })
            .collect();
        assert_eq!(simplify(&tri, 1e-6), vec![0, 50, 70, 100]);
        assert_eq!(simplify(&[], 1.0), Vec::<usize>::new());
        assert_eq!(simplify(&[[0.0, 1.0]], 1.0), vec![0]);
    }

    #[test]
    fn every_point_is_within_the_tolerance() {
        // Noisy curves of many shapes and tolerances: the bound holds, the ends are kept,
        // and the kept indices increase.
        let mut rng = Rng(11);
        for case in 0..200 {
            let n = 2 + (rng.next_u64() % 3000) as usize;
            let tol = 10f64.powf(-4.0 + 3.0 * rng.uniform());
            let amp = 10f64.powf(-3.0 + 3.0 * rng.uniform());
            let mut t = 0.0;
            let points: Vec<[f64; 2]> = (0..n)
                .map(|i| {
                    t += 0.001 + rng.uniform() * 0.01;
                    [t, (i as f64 * 0.01).sin() + amp * rng.normal()]
                })
                .collect();
            let kept = simplify(&points, tol);
            assert_eq!((kept[0], *kept.last().unwrap()), (0, n - 1), "case {case}");
            assert!(kept.windows(2).all(|w| w[0] < w[1]));
            let e = max_error(&points, &kept);
            assert!(e <= tol, "case {case}: error {e} > tolerance {tol}");
        }
    }

    #[test]
    fn interpolation_is_flat_outside() {
        let p = [[1.0, 2.0], [3.0, 6.0]];
        assert_eq!((interpolate(&p, 0.0), interpolate(&p, 2.0), interpolate(&p, 9.0)), (2.0, 4.0, 6.0));
    }
}
