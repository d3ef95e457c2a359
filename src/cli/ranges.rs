//! Numeric options: each has a stated range, its maximum included, checked when the
//! command line is parsed (exit 2 with the range in the message, never a panic). Options
//! that take them also accept a leading minus sign, so that `--incidence -10` reaches the
//! range check instead of being read as an unknown flag.

/// An integer option in `lo..=hi`.
pub fn integer<T>(lo: u64, hi: u64) -> impl Fn(&str) -> Result<T, String> + Clone + Send + Sync
where
    T: TryFrom<u64>,
{
    move |s: &str| {
        let range = || format!("give an integer in {lo}..={hi}");
        let n: i128 = s
            .trim()
            .replace('_', "")
            .parse()
            .map_err(|_| format!("`{s}` is not an integer; {}", range()))?;
        if n < i128::from(lo) || n > i128::from(hi) {
            return Err(format!("{n} is out of range; {}", range()));
        }
        T::try_from(n as u64).map_err(|_| format!("{n} does not fit this machine; {}", range()))
    }
}

/// A real option in `[lo, hi]` (or `[lo, hi)` / `(lo, hi]` with the `open_*` flags): a
/// finite number in the range.
pub fn real(
    lo: f64,
    hi: f64,
    open_lo: bool,
    open_hi: bool,
) -> impl Fn(&str) -> Result<f64, String> + Clone + Send + Sync {
    move |s: &str| {
        let range = format!(
            "give a number in {}{lo}, {hi}{}",
            if open_lo { "(" } else { "[" },
            if open_hi { ")" } else { "]" }
        );
        let x: f64 = s
            .trim()
            .parse()
            .map_err(|_| format!("`{s}` is not a number; {range}"))?;
        let inside = x.is_finite()
            && (if open_lo { x > lo } else { x >= lo })
            && (if open_hi { x < hi } else { x <= hi });
        if inside {
            Ok(x)
        } else {
            Err(format!("{s} is out of range; {range}"))
        }
    }
}

/// Largest batch `generate` and `demo` build in memory (40–52 bytes a tuple).
pub const MAX_IN_MEMORY_TUPLES: u64 = 100_000_000;
/// Largest stress corpus (evaluated in chunks, so bounded by time, not memory).
pub const MAX_STRESS_TUPLES: u64 = 10_000_000_000;
/// Largest per-combination sample of `check` and per-preset sample of `demo --check`.
pub const MAX_CHECK_TUPLES: u64 = 10_000_000;

/// A size in bytes in `lo..=hi`: a number with an optional binary unit — `K`/`KiB`,
/// `M`/`MiB`, `G`/`GiB`, `T`/`TiB` (also lower-case `k`, `m`, `g`, `t`), or none for bytes.
pub fn bytes(lo: u64, hi: u64) -> impl Fn(&str) -> Result<u64, String> + Clone + Send + Sync {
    move |s: &str| {
        let t = s.trim();
        let split = t.find(|c: char| c.is_ascii_alphabetic()).unwrap_or(t.len());
        let (num, unit) = t.split_at(split);
        let range = || format!("give a size from {} to {}", human(lo), human(hi));
        let scale: u64 = match unit.trim() {
            "" | "B" => 1,
            "K" | "k" | "KiB" => 1 << 10,
            "M" | "m" | "MiB" => 1 << 20,
            "G" | "g" | "GiB" => 1 << 30,
            "T" | "t" | "TiB" => 1 << 40,
            other => {
                return Err(format!(
                    "unknown unit `{other}`; use K, M, G or T (KiB, MiB, GiB, TiB); {}",
                    range()
                ))
            }
        };
        let n: f64 = num
            .trim()
            .parse()
            .map_err(|_| format!("`{s}` is not a size like 256M or 2GiB; {}", range()))?;
        let value = n * scale as f64;
        if !(value.is_finite() && value >= lo as f64 && value <= hi as f64) {
            return Err(format!("`{s}` is out of range; {}", range()));
        }
        Ok(value as u64)
    }
}

/// `n` bytes as the largest binary unit that divides it (`512MiB`, `1TiB`).
fn human(n: u64) -> String {
    for (unit, shift) in [("TiB", 40), ("GiB", 30), ("MiB", 20), ("KiB", 10)] {
        if n >= 1 << shift && n.is_multiple_of(1 << shift) {
            return format!("{}{unit}", n >> shift);
        }
    }
    format!("{n} bytes")
}
