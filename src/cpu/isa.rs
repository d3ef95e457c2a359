//! The instruction sets the CPU engine's lanes are compiled for, and which one runs.
//!
//! One binary carries three variants of every lane loop, chosen at run time through
//! `pulp`: AVX-512 (x86-64-v4), AVX2 with FMA (x86-64-v3) and the baseline (`scalar`,
//! SSE2 on x86-64). The best the CPU has runs unless `VKBRDF_CPU_ISA` names another
//! (`scalar`, `avx2+fma` or `avx512`, the names every report prints); naming one the CPU
//! lacks is an error, never a silent fallback. The variants may differ in the last bits
//! (lane width and FMA change roundings), each within FORMULAS.md §1's rule of the
//! reference (docs/CPU_ENGINE.md, "Instruction sets").

use crate::error::{Error, Result};

/// The environment variable that forces a variant.
pub const ENV: &str = "VKBRDF_CPU_ISA";

/// One compiled variant of the lanes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Isa {
    /// The baseline instruction set (no target features beyond the platform's default).
    Scalar,
    /// AVX2 with FMA (x86-64-v3).
    Avx2Fma,
    /// AVX-512 F/BW/CD/DQ/VL (x86-64-v4).
    Avx512,
}

impl Isa {
    /// Every variant, slowest first.
    pub const ALL: [Isa; 3] = [Isa::Scalar, Isa::Avx2Fma, Isa::Avx512];

    /// The name reports print and `VKBRDF_CPU_ISA` takes.
    pub fn name(self) -> &'static str {
        match self {
            Isa::Scalar => "scalar",
            Isa::Avx2Fma => "avx2+fma",
            Isa::Avx512 => "avx512",
        }
    }

    /// The variant called `name` (see [`Isa::name`]).
    pub fn parse(name: &str) -> Result<Isa> {
        Isa::ALL
            .into_iter()
            .find(|i| i.name() == name.trim())
            .ok_or_else(|| {
                Error::Unsupported(format!(
                    "{ENV}={name:?} is not an instruction set: use scalar, avx2+fma or avx512"
                ))
            })
    }

    /// Whether this CPU can run the variant.
    pub fn available(self) -> bool {
        self.arch().is_some()
    }

    /// The variants this CPU can run, slowest first (`scalar` always).
    pub fn available_all() -> Vec<Isa> {
        Isa::ALL.into_iter().filter(|i| i.available()).collect()
    }

    /// The fastest variant this CPU runs.
    pub fn best() -> Isa {
        *Isa::available_all().last().unwrap_or(&Isa::Scalar)
    }

    /// The variant `VKBRDF_CPU_ISA` names, or the best when it is unset or empty; an error
    /// for a name that is not a variant or one the CPU lacks.
    pub fn from_env() -> Result<Isa> {
        match std::env::var(ENV) {
            Ok(s) if !s.trim().is_empty() => {
                let isa = Isa::parse(&s)?;
                if !isa.available() {
                    return Err(Error::Unsupported(format!(
                        "{ENV}={}: this CPU cannot run that instruction set (it runs {})",
                        isa.name(),
                        Isa::available_all()
                            .iter()
                            .map(|i| i.name())
                            .collect::<Vec<_>>()
                            .join(", ")
                    )));
                }
                Ok(isa)
            }
            _ => Ok(Isa::best()),
        }
    }

    /// pulp's handle for the variant, proving the CPU has its features (`None` if not).
    pub(crate) fn arch(self) -> Option<pulp::Arch> {
        match self {
            Isa::Scalar => Some(pulp::Arch::Scalar),
            #[cfg(target_arch = "x86_64")]
            Isa::Avx2Fma => pulp::x86::V3::try_new().map(pulp::Arch::V3),
            #[cfg(target_arch = "x86_64")]
            Isa::Avx512 => pulp::x86::V4::try_new().map(pulp::Arch::V4),
            #[cfg(not(target_arch = "x86_64"))]
            _ => None,
        }
    }
}

impl std::fmt::Display for Isa {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Work in the lanes that runs fused multiply–adds where the instruction set has them:
/// [`pulp::WithSimd`] for any instruction set, [`WithFma::with_fma`] for AVX-512 and AVX2,
/// which both have FMA and the AVX transposes.
pub(super) trait WithFma: pulp::WithSimd {
    /// The work in `simd`'s lanes, with FMA.
    fn with_fma<S: super::transpose::Transpose + super::register::RegisterIo>(
        self,
        simd: S,
    ) -> Self::Output;
}

/// `op` in `arch`'s lanes: AVX-512 and AVX2 through [`WithFma::with_fma`] (inside the
/// instruction set's target features), the others through pulp's dispatch.
pub(super) fn run_lanes<O: WithFma>(arch: pulp::Arch, op: O) -> O::Output {
    #[cfg(target_arch = "x86_64")]
    match arch {
        pulp::Arch::V4(simd) => return simd.vectorize(Fma { simd, op }),
        pulp::Arch::V3(simd) => return simd.vectorize(Fma { simd, op }),
        _ => {}
    }
    arch.dispatch(op)
}

/// `op` with the instruction set `simd` that has FMA, as a function pulp compiles for it.
#[cfg(target_arch = "x86_64")]
struct Fma<S, O> {
    simd: S,
    op: O,
}

#[cfg(target_arch = "x86_64")]
impl<S: super::transpose::Transpose + super::register::RegisterIo, O: WithFma> pulp::NullaryFnOnce
    for Fma<S, O>
{
    type Output = O::Output;

    #[inline(always)]
    fn call(self) -> O::Output {
        self.op.with_fma(self.simd)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_and_scalar_is_always_there() {
        for i in Isa::ALL {
            assert_eq!(Isa::parse(i.name()).unwrap(), i);
        }
        assert!(Isa::parse("avx2").is_err());
        assert!(Isa::Scalar.available());
        assert!(Isa::available_all().contains(&Isa::best()));
    }
}
