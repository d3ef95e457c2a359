//! OpenEXR output with the `exr` crate: float32 (or float16 with `--half`) channels in one
//! or more named layers, ZIP-compressed scan lines, with the table's provenance as text
//! attributes `vkbrdf.*` in every layer's header. Written atomically.
//!
//! Channel data is row-major with row 0 first (the top of the image): texel `(i, j)` is
//! `values[j·W + i]`, matching [`TEXEL_CENTRES`].

use super::grid::{Grid, TEXEL_CENTRES, VERSION};
use crate::atomic::Staged;
use crate::cancel::Cancel;
use crate::error::{Error, Result};
use exr::prelude::{
    f16, AnyChannel, AnyChannels, AttributeValue, Encoding, FlatSamples, Image, ImageAttributes,
    IntegerBounds, Layer as ExrLayer, LayerAttributes, SmallVec, Text, WritableImage,
};
use std::io::Write;
use std::path::Path;

/// One channel of a table: a name (`R`, `Y`, `F.R`, …) and `W·H` values, row-major.
#[derive(Debug, Clone, PartialEq)]
pub struct Channel {
    /// Channel name inside its layer.
    pub name: String,
    /// `W·H` values, texel `(i, j)` at `j·W + i`.
    pub values: Vec<f32>,
}

/// A layer of channels. A file with one layer is a plain single-part EXR; a file with
/// several is multi-part, each part named by its layer's name (so channel names may repeat
/// across layers, e.g. `G` of the BRDF and `G` of the terms).
#[derive(Debug, Clone, PartialEq)]
pub struct Layer {
    /// Part name (written only in multi-part files).
    pub name: String,
    /// The channels (sorted by name on writing, as OpenEXR requires).
    pub channels: Vec<Channel>,
}

/// Where a table came from, stored as `vkbrdf.<key>` text attributes in each header.
#[derive(Debug, Clone, PartialEq)]
pub struct Provenance {
    /// Which table (`slice`, `albedo`, `albedo-average`, `dfg`).
    pub table: String,
    /// The material, or the model the table integrates, in words.
    pub material: String,
    /// The convention (§5) the material uses.
    pub convention: String,
    /// What x, y (and the channels) mean.
    pub parameterisation: String,
    /// Samples per texel and how they were taken.
    pub samples: String,
    /// The backend that evaluated f.
    pub backend: String,
}

impl Provenance {
    /// The attributes as `(name, value)`: the fields plus the texel-centre convention and
    /// the vkbrdf version.
    pub fn attributes(&self) -> Vec<(&'static str, String)> {
        vec![
            ("vkbrdf.table", self.table.clone()),
            ("vkbrdf.material", self.material.clone()),
            ("vkbrdf.convention", self.convention.clone()),
            ("vkbrdf.parameterisation", self.parameterisation.clone()),
            ("vkbrdf.texelCentres", TEXEL_CENTRES.to_string()),
            ("vkbrdf.samples", self.samples.clone()),
            ("vkbrdf.backend", self.backend.clone()),
            ("vkbrdf.version", VERSION.to_string()),
        ]
    }
}

/// Texels of one layer clamped to [`HALF_MAX`] when written as float16.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Clamped {
    /// The layer's name.
    pub layer: String,
    /// Texels with at least one channel clamped.
    pub texels: usize,
}

/// The largest finite float16, 65504: float16 values beyond it are written as it.
pub const HALF_MAX: f32 = 65504.0;

/// Writes `layers` of a `grid` table to `path` (float16 when `half`), atomically,
/// stopping when `cancel` is set.
///
/// float16 tops out at [`HALF_MAX`]: a finite value beyond it (a sharp lobe's peak, K near
/// grazing) is written as ±[`HALF_MAX`] instead of ±inf, and the layers where that happened
/// are returned with the number of texels clamped, for the caller to report.
pub fn write(
    path: &Path,
    grid: Grid,
    layers: Vec<Layer>,
    provenance: &Provenance,
    half: bool,
    cancel: &Cancel,
) -> Result<Vec<Clamped>> {
    let (staged, clamped) = stage(path, grid, layers, provenance, half, cancel)?;
    crate::atomic::commit(vec![staged])?;
    Ok(clamped)
}

/// [`write()`] without making the file visible: for tables written as a set
/// ([`crate::atomic::commit`]).
pub fn stage(
    path: &Path,
    grid: Grid,
    mut layers: Vec<Layer>,
    provenance: &Provenance,
    half: bool,
    cancel: &Cancel,
) -> Result<(Staged, Vec<Clamped>)> {
    for layer in &layers {
        for c in &layer.channels {
            if c.values.len() != grid.texels() {
                return Err(Error::Table(format!(
                    "{}: channel {}.{} holds {} values for a {}x{} table (a bug)",
                    path.display(),
                    layer.name,
                    c.name,
                    c.values.len(),
                    grid.width,
                    grid.height
                )));
            }
        }
    }
    let clamped = if half {
        layers.iter_mut().filter_map(clamp_to_half).collect()
    } else {
        Vec::new()
    };
    let multi = layers.len() > 1;
    let size = (grid.width, grid.height);
    let exr_layers: Vec<_> = layers
        .into_iter()
        .map(|layer| {
            let mut attributes = if multi {
                LayerAttributes::named(text(&layer.name))
            } else {
                LayerAttributes::default()
            };
            attributes.software_name = Some(text(&format!("vkbrdf {}", VERSION)));
            for (key, value) in provenance.attributes() {
                attributes
                    .other
                    .insert(text(key), AttributeValue::Text(text(&value)));
            }
            let channels: SmallVec<[AnyChannel<FlatSamples>; 4]> = layer
                .channels
                .into_iter()
                .map(|c| AnyChannel::new(text(&c.name), samples(c.values, half)))
                .collect();
            ExrLayer::new(
                size,
                attributes,
                Encoding::SMALL_LOSSLESS,
                AnyChannels::sort(channels),
            )
        })
        .collect();
    let image = Image::from_layers(
        ImageAttributes::new(IntegerBounds::from_dimensions(size)),
        exr_layers,
    );
    let mut encoded = std::io::Cursor::new(Vec::new());
    image
        .write()
        .to_buffered(&mut encoded)
        .map_err(|e| Error::Table(format!("{}: OpenEXR encoding: {e}", path.display())))?;
    let mut encoded = encoded.into_inner();
    sort_provenance(&mut encoded).ok_or_else(|| {
        Error::Table(format!(
            "{}: the OpenEXR encoder wrote a header this writer cannot read (a bug)",
            path.display()
        ))
    })?;
    let staged = crate::atomic::stage(path, cancel, |w| w.write_all(&encoded))?;
    Ok((staged, clamped))
}

/// Puts the `vkbrdf.*` attributes of every header of the encoded file `bytes` in name
/// order, in place. The `exr` crate keeps them in a `HashMap` and writes them in its
/// randomly seeded order, so without this the same table written twice differs in its
/// header bytes (and a merged table would differ from the unsharded one). Each header keeps
/// its length, so the offset tables after the headers stay valid. `None` when the bytes
/// are not a header this function can walk.
fn sort_provenance(bytes: &mut [u8]) -> Option<()> {
    // The version field's bit 12: several headers, ended by an empty one.
    let multi = u32::from_le_bytes(bytes.get(4..8)?.try_into().ok()?) & 0x1000 != 0;
    let nul =
        |bytes: &[u8], from: usize| Some(from + bytes.get(from..)?.iter().position(|&b| b == 0)?);
    let mut at = 8;
    loop {
        let start = at;
        // (name, byte range) of each attribute: name\0 type\0 size:i32 value.
        let mut attributes: Vec<(Vec<u8>, std::ops::Range<usize>)> = Vec::new();
        loop {
            let name_end = nul(bytes, at)?;
            if name_end == at {
                at += 1; // the header's closing \0
                break;
            }
            let type_end = nul(bytes, name_end + 1)?;
            let size = i32::from_le_bytes(bytes.get(type_end + 1..type_end + 5)?.try_into().ok()?);
            let end = type_end + 5 + usize::try_from(size).ok()?;
            if end > bytes.len() {
                return None;
            }
            attributes.push((bytes[at..name_end].to_vec(), at..end));
            at = end;
        }
        let ours = |name: &[u8]| name.starts_with(b"vkbrdf.");
        let mut sorted: Vec<&(Vec<u8>, std::ops::Range<usize>)> =
            attributes.iter().filter(|(n, _)| ours(n)).collect();
        sorted.sort_by(|a, b| a.0.cmp(&b.0));
        let mut sorted = sorted.into_iter();
        let mut header = Vec::with_capacity(at - start);
        for attribute in &attributes {
            let (_, range) = if ours(&attribute.0) {
                sorted.next()?
            } else {
                attribute
            };
            header.extend_from_slice(&bytes[range.clone()]);
        }
        bytes[start..at - 1].copy_from_slice(&header);
        if !multi || *bytes.get(at)? == 0 {
            return Some(());
        }
    }
}

/// Clamps `layer`'s finite values to ±[`HALF_MAX`] (which float16 would round to ±inf
/// beyond 65520); returns the layer and its clamped texels, if any. Non-finite values are
/// left alone: they are not an overflow of the format.
fn clamp_to_half(layer: &mut Layer) -> Option<Clamped> {
    let texels = layer.channels.first().map_or(0, |c| c.values.len());
    let mut hit = vec![false; texels];
    for c in &mut layer.channels {
        for (x, hit) in c.values.iter_mut().zip(&mut hit) {
            if x.is_finite() && x.abs() > HALF_MAX {
                *x = HALF_MAX.copysign(*x);
                *hit = true;
            }
        }
    }
    let texels = hit.iter().filter(|&&h| h).count();
    (texels > 0).then(|| Clamped {
        layer: layer.name.clone(),
        texels,
    })
}

/// float32 samples, or float16 when `half`.
fn samples(values: Vec<f32>, half: bool) -> FlatSamples {
    if half {
        FlatSamples::F16(values.into_iter().map(f16::from_f32).collect())
    } else {
        FlatSamples::F32(values)
    }
}

/// An EXR text (Latin-1); characters beyond it are written as `\u{…}` escapes.
fn text(s: &str) -> Text {
    Text::new_or_none(s).unwrap_or_else(|| {
        let escaped: String = s
            .chars()
            .map(|c| {
                if (c as u32) < 256 {
                    c.to_string()
                } else {
                    c.escape_unicode().to_string()
                }
            })
            .collect();
        Text::new_or_panic(escaped)
    })
}
