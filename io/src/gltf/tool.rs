use fem_core::press::Protocol;

use super::scene::{AnimatedTool, ToolKey};

impl AnimatedTool {
    /// A box `lo <= x <= hi` [mm] in the tool's frame, with flat faces (four
    /// vertices of its own per face), moved by `keys`.
    pub fn cuboid(name: &str, lo_mm: [f64; 3], hi_mm: [f64; 3], keys: Vec<ToolKey>) -> Self {
        let mut vertices_mm = Vec::with_capacity(24);
        let mut triangles = Vec::with_capacity(12);
        for axis in 0..3 {
            let (u, w) = ((axis + 1) % 3, (axis + 2) % 3);
            for (side, sign) in [(hi_mm[axis], 1.0), (lo_mm[axis], -1.0)] {
                let corner = |a: f64, b: f64| {
                    let mut p = [0.0; 3];
                    p[axis] = side;
                    p[u] = a;
                    p[w] = b;
                    p
                };
                let base = vertices_mm.len() as u32;
                vertices_mm.extend([
                    corner(lo_mm[u], lo_mm[w]),
                    corner(hi_mm[u], lo_mm[w]),
                    corner(hi_mm[u], hi_mm[w]),
                    corner(lo_mm[u], hi_mm[w]),
                ]);
                // (u, w, axis) is a cyclic, right-handed order: u x w = +axis.
                if sign > 0.0 {
                    triangles.extend([[base, base + 1, base + 2], [base, base + 2, base + 3]]);
                } else {
                    triangles.extend([[base, base + 2, base + 1], [base, base + 3, base + 2]]);
                }
            }
        }
        Self { name: name.to_string(), vertices_mm, triangles, keys }
    }

    /// The seed's plate, for a specimen whose reference surface spans
    /// `specimen_bounds_mm` (`(min, max)`, y up): a flat box overhanging the top
    /// face by 15 % of its larger side all round, its underside at the top face's
    /// height `y_top` at first touch and at `y_top - d(t)` afterwards, following
    /// `protocol.displacement(t)` (keys at every waypoint) until `release_s`.
    /// After the release it rises, over 5 % of the trial (at most until `end_s`),
    /// to 15 % of the specimen's height above `y_top`, and stays there: a picture
    /// of the plate letting go, not a simulated motion.
    pub fn plate(protocol: &Protocol, specimen_bounds_mm: ([f64; 3], [f64; 3])) -> Self {
        let (lo, hi) = specimen_bounds_mm;
        let span = (hi[0] - lo[0]).max(hi[2] - lo[2]);
        let overhang = 0.15 * span;
        let thickness = 0.06 * span;
        let y_top = hi[1];
        let end = protocol.end_s;
        let last = protocol.release_s.min(end);
        let at = |t: f64| ToolKey::translated(t, [0.0, y_top - protocol.displacement(t), 0.0]);
        let mut times: Vec<f64> = vec![0.0];
        times.extend(protocol.waypoints.iter().map(|w| w[0]).filter(|&t| t > 0.0 && t < last));
        times.push(last);
        let mut keys: Vec<ToolKey> = times.into_iter().map(at).collect();
        let rise_s = (0.05 * end).min(end - protocol.release_s);
        if protocol.release_s < end && rise_s > 0.0 {
            let clearance = y_top + 0.15 * (hi[1] - lo[1]);
            let from = keys.last().map_or(y_top, |k| k.translation_mm[1]);
            keys.push(ToolKey::translated(protocol.release_s + rise_s, [0.0, clearance.max(from), 0.0]));
        }
        Self::cuboid(
            "plate",
            [lo[0] - overhang, 0.0, lo[2] - overhang],
            [hi[0] + overhang, thickness, hi[2] + overhang],
            strictly_increasing(keys),
        )
    }
}

/// Drops keys whose time (as glTF's f32) is not after the one kept before.
fn strictly_increasing(keys: Vec<ToolKey>) -> Vec<ToolKey> {
    let mut out: Vec<ToolKey> = Vec::with_capacity(keys.len());
    for key in keys {
        match out.last() {
            Some(p) if !(key.t_s.is_finite() && (key.t_s as f32) > (p.t_s as f32)) => {}
            _ => out.push(key),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_cuboid_has_outward_faces() {
        let c = AnimatedTool::cuboid("c", [0.0, 0.0, 0.0], [1.0, 2.0, 3.0], Vec::new());
        assert_eq!((c.vertices_mm.len(), c.triangles.len()), (24, 12));
        let centre = [0.5, 1.0, 1.5];
        let mut volume = 0.0;
        for t in &c.triangles {
            let [a, b, d] = t.map(|v| c.vertices_mm[v as usize]);
            let e1 = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
            let e2 = [d[0] - a[0], d[1] - a[1], d[2] - a[2]];
            let n = [e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]];
            let out = [a[0] - centre[0], a[1] - centre[1], a[2] - centre[2]];
            assert!(n[0] * out[0] + n[1] * out[1] + n[2] * out[2] > 0.0, "inward face {t:?}");
            volume += (a[0] * (b[1] * d[2] - b[2] * d[1])
                + a[1] * (b[2] * d[0] - b[0] * d[2])
                + a[2] * (b[0] * d[1] - b[1] * d[0]))
                / 6.0;
        }
        assert!((volume - 6.0).abs() < 1e-12, "{volume}");
    }

    #[test]
    fn the_plate_follows_the_protocol_then_rises() {
        let protocol = Protocol::ramp_hold_release(0.2, 28.87, 210.93, 400.0);
        let plate = AnimatedTool::plate(&protocol, ([0.0, 0.0, 0.0], [58.0, 59.5, 12.0]));
        let t: Vec<f64> = plate.keys.iter().map(|k| k.t_s).collect();
        assert_eq!(t, vec![0.0, 28.87, 210.93, 230.93]);
        let y: Vec<f64> = plate.keys.iter().map(|k| k.translation_mm[1]).collect();
        assert_eq!(y[0], 59.5);
        assert!((y[1] - (59.5 - 5.774)).abs() < 1e-12 && (y[2] - y[1]).abs() < 1e-12);
        assert!((y[3] - (59.5 + 0.15 * 59.5)).abs() < 1e-12);
        // Overhangs the 58 x 12 top face.
        let x: Vec<f64> = plate.vertices_mm.iter().map(|p| p[0]).collect();
        assert!(x.iter().copied().fold(f64::INFINITY, f64::min) < 0.0);
        assert!(x.iter().copied().fold(f64::NEG_INFINITY, f64::max) > 58.0);

        // Released at the end: no rise.
        let held = Protocol::ramp_hold_release(0.2, 10.0, 20.0, 20.0);
        let plate = AnimatedTool::plate(&held, ([0.0, 0.0, 0.0], [1.0, 1.0, 1.0]));
        assert_eq!(plate.keys.iter().map(|k| k.t_s).collect::<Vec<_>>(), vec![0.0, 10.0, 20.0]);
    }
}
