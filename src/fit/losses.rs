//! The losses people publish (docs/FITTING.md, "Losses"), all computed for every fit
//! whichever one is minimised. `f` is the model, `f_m` the measurement, per RGB channel,
//! summed over the channels; `w` the sample's weight ([`super::data::Measure`]).

use super::data::FitData;

/// The loss a fit minimises (`--loss`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum Loss {
    /// Ngan, Durand & Matusik 2005: `Σ w ((f − f_m) cos θ_i)²`, `w` = `sin θ_i sin θ_o`
    /// on an angle grid (the default).
    #[default]
    L2,
    /// Löw et al. 2012, E1: `Σ w ((f − f_m) cos θ_i)²`, `w` = `sin θ_i` on an angle grid.
    E1,
    /// Löw et al. 2012, E2: `Σ w (ln(1 + f cos θ_i) − ln(1 + f_m cos θ_i))²`.
    E2,
    /// Relative RMS: `sqrt(Σ w ((f − f_m)/max(f_m, ε))² / Σ w)` over the samples and
    /// channels, ε = [`RRMS_FLOOR`].
    Rrms,
}

/// The floor of the relative RMS's denominator, in 1/sr: 1e-3, about what a MERL file
/// resolves (its 16-bit-era measurements store f / scale with scale 1/1500), so that
/// near-black samples do not dominate it.
pub const RRMS_FLOOR: f64 = 1e-3;

impl Loss {
    /// Every loss, in the order the report lists them.
    pub const ALL: [Loss; 4] = [Loss::L2, Loss::E1, Loss::E2, Loss::Rrms];

    /// The name `--loss` takes.
    pub fn name(self) -> &'static str {
        match self {
            Loss::L2 => "l2",
            Loss::E1 => "e1",
            Loss::E2 => "e2",
            Loss::Rrms => "rrms",
        }
    }

    /// Whether the loss is a weighted sum of squares of `f − f_m`, so that the linear
    /// parameters are solved exactly inside each evaluation (L2 and E1).
    pub fn is_quadratic(self) -> bool {
        matches!(self, Loss::L2 | Loss::E1)
    }

    /// The quadratic losses' weight of sample `i` (`w cos² θ_i`).
    pub fn quadratic_weight(self, data: &FitData, i: usize) -> f64 {
        let w = match self {
            Loss::L2 => data.weight_l2[i],
            _ => data.weight_e[i],
        };
        w * data.cos_i[i] * data.cos_i[i]
    }
}

impl std::str::FromStr for Loss {
    type Err = crate::Error;
    fn from_str(s: &str) -> crate::Result<Loss> {
        Loss::ALL
            .into_iter()
            .find(|l| l.name() == s)
            .ok_or_else(|| {
                crate::Error::Unsupported(format!(
                    "unknown loss `{s}`; expected one of: l2, e1, e2, rrms"
                ))
            })
    }
}

/// Every metric of a model against the data.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Metrics {
    /// Ngan's L2.
    pub l2: f64,
    /// L2 divided by the data's energy (`Σ w (f_m cos θ_i)²`, the L2 of f = 0).
    pub l2_relative: f64,
    /// Löw's E1.
    pub e1: f64,
    /// Löw's E2.
    pub e2: f64,
    /// The relative RMS.
    pub rrms: f64,
    /// The data's energy, `Σ w (f_m cos θ_i)²` (L2's weights).
    pub energy: f64,
}

impl Metrics {
    /// The value of `loss`.
    pub fn get(&self, loss: Loss) -> f64 {
        match loss {
            Loss::L2 => self.l2,
            Loss::E1 => self.e1,
            Loss::E2 => self.e2,
            Loss::Rrms => self.rrms,
        }
    }
}

/// Every metric of `model` (f per sample, RGB) against `data`.
pub fn metrics(data: &FitData, model: &[[f64; 3]]) -> Metrics {
    let mut m = Metrics::default();
    let mut rel = 0.0;
    let mut total = 0.0;
    for (i, (f, fm)) in model.iter().zip(&data.values).enumerate() {
        let (c, wl, we) = (data.cos_i[i], data.weight_l2[i], data.weight_e[i]);
        total += 3.0 * we;
        for ch in 0..3 {
            let d = (f[ch] - fm[ch]) * c;
            m.l2 += wl * d * d;
            m.e1 += we * d * d;
            m.energy += wl * (fm[ch] * c).powi(2);
            let e = (f[ch] * c).ln_1p() - (fm[ch] * c).ln_1p();
            m.e2 += we * e * e;
            let r = (f[ch] - fm[ch]) / fm[ch].max(RRMS_FLOOR);
            rel += we * r * r;
        }
    }
    m.rrms = if total > 0.0 {
        (rel / total).sqrt()
    } else {
        0.0
    };
    m.l2_relative = if m.energy > 0.0 { m.l2 / m.energy } else { 0.0 };
    m
}

/// The value of `loss` only (the optimiser's inner loop for E2 and the relative RMS).
pub fn value(loss: Loss, data: &FitData, model: &[[f64; 3]]) -> f64 {
    match loss {
        Loss::E2 => model
            .iter()
            .zip(&data.values)
            .enumerate()
            .map(|(i, (f, fm))| {
                let c = data.cos_i[i];
                let s: f64 = (0..3)
                    .map(|ch| ((f[ch] * c).ln_1p() - (fm[ch] * c).ln_1p()).powi(2))
                    .sum();
                data.weight_e[i] * s
            })
            .sum(),
        _ => metrics(data, model).get(loss),
    }
}
