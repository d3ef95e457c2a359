//! The wavelengths a spectral evaluation samples: a range `START:END:STEP` (nm, both ends
//! included) or a comma-separated list.

use super::cie;

/// The most wavelengths one evaluation takes (the outputs are `(n, W)` float32).
pub const MAX_WAVELENGTHS: usize = 4096;

/// Wavelengths in nm, each in [`RANGE_NM`], in the order given.
#[derive(Debug, Clone, PartialEq)]
pub struct Wavelengths(pub Vec<f64>);

/// Wavelengths vkbrdf accepts, in nm (ultraviolet to mid-infrared; a material's data may
/// cover less, and says so).
pub const RANGE_NM: (f64, f64) = (100.0, 20_000.0);

impl Wavelengths {
    /// The CIE grid 360:830:5, the one the colour reductions integrate over.
    pub fn cie() -> Wavelengths {
        Wavelengths((0..cie::SAMPLES).map(cie::wavelength).collect())
    }

    /// Whether these are exactly the CIE grid (what `--color` needs).
    pub fn is_cie_grid(&self) -> bool {
        *self == Wavelengths::cie()
    }

    /// How many.
    pub fn len(&self) -> usize {
        self.0.len()
    }

    /// Never true for a parsed value (kept for the convention that `len` has it).
    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }
}

impl std::str::FromStr for Wavelengths {
    type Err = String;

    fn from_str(s: &str) -> Result<Wavelengths, String> {
        let num = |x: &str| {
            x.trim()
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| format!("`{x}` is not a number (wavelengths are in nm)"))
        };
        let out: Vec<f64> = if s.contains(':') {
            let parts: Vec<&str> = s.split(':').collect();
            let [a, b, step] = parts.as_slice() else {
                return Err(format!(
                    "`{s}`: a range is START:END:STEP in nm, e.g. 360:830:5"
                ));
            };
            let (a, b, step) = (num(a)?, num(b)?, num(step)?);
            if !(step > 0.0 && b >= a) {
                return Err(format!("`{s}`: need END ≥ START and STEP > 0"));
            }
            let count = ((b - a) / step + 1e-9).floor() as usize + 1;
            if count > MAX_WAVELENGTHS {
                return Err(format!(
                    "`{s}` gives {count} wavelengths; at most {MAX_WAVELENGTHS}"
                ));
            }
            // Each from its index (no accumulated rounding): 360:830:5 gives exactly 360, 365, ….
            (0..count).map(|i| a + step * i as f64).collect()
        } else {
            s.split(',').map(num).collect::<Result<_, _>>()?
        };
        if out.is_empty() || out.len() > MAX_WAVELENGTHS {
            return Err(format!(
                "`{s}`: between 1 and {MAX_WAVELENGTHS} wavelengths"
            ));
        }
        if let Some(x) = out.iter().find(|x| !(RANGE_NM.0..=RANGE_NM.1).contains(*x)) {
            return Err(format!(
                "{x} nm is outside [{}, {}] nm",
                RANGE_NM.0, RANGE_NM.1
            ));
        }
        Ok(Wavelengths(out))
    }
}

#[cfg(test)]
mod tests {
    use super::Wavelengths;

    #[test]
    fn ranges_and_lists_parse() {
        let w: Wavelengths = "360:830:5".parse().unwrap();
        assert!(w.is_cie_grid() && w.len() == 95);
        assert_eq!(
            "450, 550,650".parse::<Wavelengths>().unwrap().0,
            vec![450.0, 550.0, 650.0]
        );
        assert!(!"400:700:10".parse::<Wavelengths>().unwrap().is_cie_grid());
        for bad in [
            "",
            "a",
            "830:360:5",
            "360:830:0",
            "50",
            "1:2",
            "360:830:0.001",
        ] {
            assert!(bad.parse::<Wavelengths>().is_err(), "{bad}");
        }
    }
}
