//! Writing a MERL binary's stored values (R, G, B blocks), atomically: below the whole
//! table's export ([`super::merl`]) and the merge of its shards ([`super::shard`]).

use crate::error::{Error, Result};
use crate::material::merl::{PHI_D_BINS, SAMPLES, THETA_D_BINS, THETA_H_BINS};
use std::path::Path;

/// Writes stored values (R, G, B blocks) as a MERL binary, atomically.
pub fn write_values(path: &Path, values: &[f64]) -> Result<()> {
    write_values_cancellable(path, values, &crate::cancel::Cancel::new())
}

/// [`write_values`], stopping when `cancel` is set.
pub fn write_values_cancellable(
    path: &Path,
    values: &[f64],
    cancel: &crate::cancel::Cancel,
) -> Result<()> {
    if values.len() != 3 * SAMPLES {
        return Err(Error::Table(format!(
            "{}: {} values given, a MERL table holds {}",
            path.display(),
            values.len(),
            3 * SAMPLES
        )));
    }
    crate::atomic::write_cancellable(path, cancel, |w| {
        use std::io::Write;
        for dim in [THETA_H_BINS, THETA_D_BINS, PHI_D_BINS] {
            w.write_all(&(dim as i32).to_le_bytes())?;
        }
        for x in values {
            w.write_all(&x.to_le_bytes())?;
        }
        Ok(())
    })
}
