//! Step 2, WHERE: the residuals cut into cells (phase x channel x region) and
//! segments (one trial's contiguous run of one series inside a cell), the smooth
//! test per cell and Holm's rule over the cells.
//!
//! Per cell `c`: `T_c = sum over its segments of |Q^T r|^2` with `Q` the
//! segment's orthonormal Legendre basis of degree <= 3 ([`super::stats`]),
//! chi-square with `sum dim Q` degrees of freedom under the noise model; its
//! p-value, the RMS of the residuals in noise units, the systematic fraction
//! `T_c / |r_c|^2` (about `dim / n` for noise, near 1 for a structural gap), and
//! the mean residual (its sign). A cell is flagged when Holm's rule at
//! `alpha` (default 1e-3) over all cells rejects it.

use std::collections::BTreeMap;

use super::model::{Model, ObsChannel, Phase, Region};
use super::stats::{chi2_sf, dot, holm, legendre_basis};

/// The largest Legendre degree of the smooth test.
pub const SMOOTH_DEGREE: usize = 3;

/// A cell's key.
pub type CellKey = (Phase, ObsChannel, Region);

/// One trial's contiguous run of one series inside a cell.
#[derive(Debug, Clone)]
pub struct Segment {
    /// The cell.
    pub cell: CellKey,
    /// The trial.
    pub trial: usize,
    /// Residual indices, in time order.
    pub indices: Vec<usize>,
    /// The orthonormal smooth basis on the segment's times.
    pub basis: Vec<Vec<f64>>,
}

impl Segment {
    /// `|Q^T r_seg|^2`.
    pub fn smooth(&self, r: &[f64]) -> f64 {
        let v: Vec<f64> = self.indices.iter().map(|&i| r[i]).collect();
        self.basis.iter().map(|q| dot(q, &v).powi(2)).sum()
    }

    /// `|r_seg|^2`.
    pub fn energy(&self, r: &[f64]) -> f64 {
        self.indices.iter().map(|&i| r[i] * r[i]).sum()
    }

    /// The smooth test's degrees of freedom.
    pub fn dof(&self) -> usize {
        self.basis.len()
    }
}

/// The segments of a model's residuals.
pub fn segments(model: &Model) -> Vec<Segment> {
    // Run ids: a new run whenever a series' phase changes.
    let mut last: BTreeMap<(usize, usize), (Phase, usize)> = BTreeMap::new();
    let mut groups: BTreeMap<(CellKey, usize, usize, usize), Vec<usize>> = BTreeMap::new();
    for (i, o) in model.observations.iter().enumerate() {
        let entry = last.entry((o.trial, o.series)).or_insert((o.phase, 0));
        if entry.0 != o.phase {
            *entry = (o.phase, entry.1 + 1);
        }
        let run = entry.1;
        groups.entry(((o.phase, o.channel, o.region), o.trial, o.series, run)).or_default().push(i);
    }
    groups
        .into_iter()
        .map(|((cell, trial, _, _), indices)| {
            let times: Vec<f64> = indices.iter().map(|&i| model.observations[i].t_s).collect();
            Segment { cell, trial, basis: legendre_basis(&times, SMOOTH_DEGREE), indices }
        })
        .collect()
}

/// One cell of the WHERE table.
#[derive(Debug, Clone, PartialEq)]
pub struct Cell {
    /// Phase.
    pub phase: Phase,
    /// Channel.
    pub channel: ObsChannel,
    /// Region.
    pub region: Region,
    /// Residuals in the cell.
    pub n: usize,
    /// Degrees of freedom of the smooth test.
    pub dof: usize,
    /// The smooth statistic `T_c`.
    pub statistic: f64,
    /// Its p-value.
    pub p_value: f64,
    /// Flagged by Holm's rule.
    pub flagged: bool,
    /// RMS of the residuals [noise units].
    pub rms_noise_units: f64,
    /// Mean residual [noise units] (simulated minus measured).
    pub mean_noise_units: f64,
    /// `T_c / |r_c|^2`.
    pub systematic_fraction: f64,
}

impl Cell {
    /// `phase/channel/region`.
    pub fn label(&self) -> String {
        format!("{}/{}/{}", self.phase.as_str(), self.channel.as_str(), self.region.as_str())
    }
}

/// The WHERE table of residuals `r` (in the model's residual order) over `segments`.
pub fn where_table(segments: &[Segment], r: &[f64], alpha: f64) -> Vec<Cell> {
    let mut acc: BTreeMap<CellKey, (usize, usize, f64, f64, f64)> = BTreeMap::new();
    for s in segments {
        let e = acc.entry(s.cell).or_insert((0, 0, 0.0, 0.0, 0.0));
        e.0 += s.indices.len();
        e.1 += s.dof();
        e.2 += s.smooth(r);
        e.3 += s.energy(r);
        e.4 += s.indices.iter().map(|&i| r[i]).sum::<f64>();
    }
    let mut cells: Vec<Cell> = acc
        .into_iter()
        .map(|((phase, channel, region), (n, dof, t, energy, sum))| Cell {
            phase,
            channel,
            region,
            n,
            dof,
            statistic: t,
            p_value: chi2_sf(t, dof),
            flagged: false,
            rms_noise_units: (energy / n as f64).sqrt(),
            mean_noise_units: sum / n as f64,
            systematic_fraction: if energy > 0.0 { t / energy } else { 0.0 },
        })
        .collect();
    let p: Vec<f64> = cells.iter().map(|c| c.p_value).collect();
    for (c, f) in cells.iter_mut().zip(holm(&p, alpha)) {
        c.flagged = f;
    }
    cells
}
