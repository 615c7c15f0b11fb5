//! GeoTIFF elevation rasters (`.tif`, `.tiff`) through the pure-Rust `tiff` crate: one band of
//! integer or floating-point heights, uncompressed, LZW or deflate, in strips or tiles.
//!
//! Georeferencing is read from the GeoTIFF tags a north-up raster carries:
//! `ModelPixelScaleTag` (33550, the cell sizes `[sx, sy, sz]`) and `ModelTiepointTag` (33922,
//! the raster point `(i, j)` that sits at map point `(X, Y)`). The raster type
//! (`GTRasterTypeGeoKey` in the `GeoKeyDirectoryTag`) says whether `(i, j) = (0, 0)` is the
//! north-west corner of the first cell (PixelIsArea, the default) or its centre (PixelIsPoint).
//! GDAL's `GDAL_NODATA` tag (42113) gives the holes. A rotated or sheared raster
//! (`ModelTransformationTag` only) and cells that are not square are refused.

use std::fs::File;
use std::io::{BufReader, BufWriter};
use std::path::Path;

use tiff::decoder::{Decoder, DecodingResult, Limits};
use tiff::tags::Tag;

use crate::error::DemError;
use crate::limits::Budget;
use crate::raster::{MAX_CELLS, Raster};

/// The largest compression ratio a raster's declared size may imply before it is decoded.
const MAX_COMPRESSION: u64 = 1024;

/// GTRasterTypeGeoKey, and its PixelIsPoint value.
const RASTER_TYPE_KEY: u16 = 1025;
/// GTModelTypeGeoKey and its value for longitude/latitude coordinates (GeoTIFF 1.1, §7.1.3).
const MODEL_TYPE_KEY: u16 = 1024;
const MODEL_TYPE_GEOGRAPHIC: u16 = 2;
const PIXEL_IS_POINT: u16 = 2;

/// Reads the GeoTIFF at `path` (its first image), within `budget` bytes of memory if given.
pub fn read(path: &Path, budget: Budget) -> Result<Raster, DemError> {
    let file = path.display().to_string();
    let io = |source| DemError::Io { file: file.clone(), source };
    let problem = |p: String| DemError::GeoTiff { file: file.clone(), problem: p };
    let tiff = |e: tiff::TiffError| problem(format!("not a readable TIFF: {e}"));
    crate::limits::regular_file(path)?;
    let f = File::open(path).map_err(io)?;
    let bytes = f.metadata().map_err(io)?.len();
    let mut limits = Limits::default();
    // the decoder refuses, before allocating, an image larger than this
    limits.decoding_buffer_size = (MAX_CELLS * 8) as usize;
    let mut d = Decoder::new(BufReader::new(f)).map_err(tiff)?.with_limits(limits);
    let (w, h) = d.dimensions().map_err(tiff)?;
    let (cols, rows) = (u64::from(w), u64::from(h));
    let size = |p: String| DemError::Size { file: file.clone(), cols, rows, problem: p };
    if cols * rows > MAX_CELLS {
        return Err(size(format!("more than the {MAX_CELLS} cells a raster may have")));
    }
    let bits = match d.colortype().map_err(tiff)? {
        tiff::ColorType::Gray(b) => u64::from(b),
        other => {
            return Err(problem(format!(
                "{other:?} pixels: an elevation raster has one band of heights"
            )));
        }
    };
    let compression: u16 = d.find_tag_unsigned(Tag::Compression).map_err(tiff)?.unwrap_or(1);
    let declared = cols * rows * bits / 8;
    // the decoded image and the heights as f64
    let need = declared + cols * rows * 8;
    if budget.is_some_and(|(room, _)| need > room) {
        return Err(crate::limits::too_big(&file, Some((cols, rows)), need, budget));
    }
    if compression == 1 && declared > bytes {
        return Err(size(format!(
            "{declared} bytes of uncompressed heights, but the file has {bytes} bytes (truncated?)"
        )));
    }
    // compressed: elevation data compresses far less than this even over large nodata areas
    if declared > bytes.saturating_mul(MAX_COMPRESSION) {
        return Err(size(format!(
            "{declared} bytes of heights from a file of {bytes} bytes: more than \
             {MAX_COMPRESSION}× compression, so the header is not to be trusted"
        )));
    }
    let f64s = |tag: Tag, d: &mut Decoder<BufReader<File>>| -> Result<Option<Vec<f64>>, DemError> {
        d.find_tag(tag)
            .map_err(tiff)?
            .map(|v| v.into_f64_vec().map_err(|e| problem(format!("tag {tag:?}: {e}"))))
            .transpose()
    };
    let scale = f64s(Tag::ModelPixelScaleTag, &mut d)?;
    let tie = f64s(Tag::ModelTiepointTag, &mut d)?;
    let (scale, tie) = match (scale, tie) {
        (Some(s), Some(t)) if s.len() >= 2 && t.len() >= 6 => (s, t),
        _ => {
            let why = if d.find_tag(Tag::ModelTransformationTag).map_err(tiff)?.is_some() {
                "it is placed by a ModelTransformationTag (rotated or sheared); warp it north-up \
                 (e.g. `gdalwarp`)"
            } else {
                "it has no ModelPixelScaleTag and ModelTiepointTag: it is a plain TIFF, not a \
                 GeoTIFF; export the DEM as a GeoTIFF or an ESRI ASCII grid"
            };
            return Err(problem(format!("cannot place the raster on the map: {why}")));
        }
    };
    let (sx, sy) = (scale[0], scale[1]);
    if !(sx.is_finite() && sx > 0.0 && sy.is_finite() && sy > 0.0) {
        return Err(problem(format!("pixel scale ({sx}, {sy}) is not two positive lengths")));
    }
    if (sx - sy).abs() > 1e-9 * sx.max(sy) {
        return Err(DemError::NonSquareCells { file: file.clone(), dx: sx, dy: sy });
    }
    let keys: Vec<u16> = d
        .find_tag(Tag::GeoKeyDirectoryTag)
        .map_err(tiff)?
        .and_then(|v| v.into_u16_vec().ok())
        .unwrap_or_default();
    // (key, value) of the directory's short values (its first four shorts are its header)
    let key = |id: u16| {
        let count = keys.get(3).map_or(0, |&n| usize::from(n));
        keys.get(4..)
            .unwrap_or(&[])
            .chunks_exact(4)
            .take(count)
            .find(|k| k[0] == id && k[1] == 0)
            .map(|k| k[3])
    };
    if key(MODEL_TYPE_KEY) == Some(MODEL_TYPE_GEOGRAPHIC) {
        return Err(DemError::Geographic {
            file: file.clone(),
            evidence: "its GeoKeys declare a geographic model (GTModelTypeGeoKey = 2)".into(),
        });
    }
    let point = key(RASTER_TYPE_KEY) == Some(PIXEL_IS_POINT);
    // the map point of raster point (0, 0): the first cell's corner, or its centre
    let (i, j, x, y) = (tie[0], tie[1], tie[3], tie[4]);
    let shift = if point { 0.5 } else { 0.0 };
    let west = x - (i + shift) * sx;
    let north = y + (j + shift) * sy;
    let nodata = match d.find_tag(Tag::GdalNodata).map_err(tiff)? {
        Some(v) => {
            let s = v.into_string().map_err(|e| problem(format!("GDAL_NODATA tag: {e}")))?;
            let s = s.trim_matches(|c: char| c == '\0' || c.is_whitespace());
            Some(
                s.parse::<f64>()
                    .map_err(|_| problem(format!("GDAL_NODATA tag `{s}` is not a number")))?,
            )
        }
        None => None,
    };
    let z = match d.read_image().map_err(|e| problem(format!("cannot decode the heights: {e}")))? {
        DecodingResult::U8(v) => v.into_iter().map(f64::from).collect(),
        DecodingResult::U16(v) => v.into_iter().map(f64::from).collect(),
        DecodingResult::U32(v) => v.into_iter().map(f64::from).collect(),
        DecodingResult::I8(v) => v.into_iter().map(f64::from).collect(),
        DecodingResult::I16(v) => v.into_iter().map(f64::from).collect(),
        DecodingResult::I32(v) => v.into_iter().map(f64::from).collect(),
        DecodingResult::F32(v) => v.into_iter().map(f64::from).collect(),
        DecodingResult::F64(v) => v,
        other => {
            return Err(problem(format!(
                "heights stored as {}: use 8–32-bit integers or 32/64-bit floats",
                match other {
                    DecodingResult::U64(_) | DecodingResult::I64(_) => "64-bit integers",
                    _ => "16-bit floats",
                }
            )));
        }
    };
    // a nodata value given as text for float heights compares at the heights' precision
    let nodata = nodata.map(|d| match z.iter().find(|v| (**v - d).abs() <= 1e-6 * d.abs()) {
        Some(&v) => v,
        None => d,
    });
    // The CRS is carried, not used: a parameter tag that cannot be read (or written again: the
    // TIFF writer takes ASCII text only) is left out with the keys that point into it, and
    // never fails the read.
    let doubles: Option<Vec<f64>> =
        d.find_tag(Tag::GeoDoubleParamsTag).ok().flatten().and_then(|v| v.into_f64_vec().ok());
    let ascii: Option<String> = d
        .find_tag(Tag::GeoAsciiParamsTag)
        .ok()
        .flatten()
        .and_then(|v| v.into_string().ok())
        // (without the terminating NUL, which writing adds again)
        .map(|t| t.trim_end_matches('\0').to_string())
        .filter(|t| t.is_ascii() && !t.contains('\0'));
    let crs = crate::Crs { geokeys: carried_keys(keys, doubles, ascii), wkt: None };
    Ok(Raster::new(&file, [w as usize, h as usize], sx, [west, north], z, nodata)?
        .plausible_heights()?
        .with_crs(crs))
}

/// The GeoKeys to carry from a directory `keys` and its parameter tags: every key whose value
/// is inline or in a parameter tag that was read, in the directory's order (a key whose values
/// lie inside the directory itself, location 34735, is left out: rare, and its offset would not
/// survive the directory being rebuilt). `None` without a directory.
fn carried_keys(
    keys: Vec<u16>,
    doubles: Option<Vec<f64>>,
    ascii: Option<String>,
) -> Option<(Vec<u16>, Vec<f64>, String)> {
    let header = keys.get(..4)?;
    let count = usize::from(header[3]);
    let entries: Vec<&[u16]> = keys[4..].chunks_exact(4).take(count).collect();
    let (doubles, ascii) = (doubles.unwrap_or_default(), ascii.unwrap_or_default());
    let fits = |e: &[u16], len: usize| usize::from(e[3]) + usize::from(e[2]) <= len;
    let kept: Vec<&[u16]> = entries
        .into_iter()
        .filter(|e| match e[1] {
            0 => true,
            34736 => fits(e, doubles.len()),
            34737 => fits(e, ascii.len()),
            _ => false,
        })
        .collect();
    let mut out = vec![header[0], header[1], header[2], kept.len() as u16];
    out.extend(kept.into_iter().flatten());
    Some((out, doubles, ascii))
}

/// The GeoKeyDirectory a written raster carries: its CRS's keys, if it has any, with
/// GTRasterTypeGeoKey set to PixelIsArea (the corner convention [`write`] uses); otherwise that
/// key alone. Entries sorted by key id, as the GeoTIFF specification requires.
fn directory(crs: &crate::Crs) -> Vec<u16> {
    let mut entries: Vec<[u16; 4]> = crs.geokeys.as_ref().map_or(Vec::new(), |(keys, _, _)| {
        let count = keys.get(3).map_or(0, |&n| usize::from(n));
        let body = keys.get(4..).unwrap_or(&[]);
        body.chunks_exact(4).take(count).map(|k| [k[0], k[1], k[2], k[3]]).collect()
    });
    entries.retain(|e| e[0] != RASTER_TYPE_KEY);
    entries.push([RASTER_TYPE_KEY, 0, 1, 1]);
    entries.sort_by_key(|e| e[0]);
    // the source's version and revision (GeoTIFF 1.0 or 1.1), 1.1.0 for a raster made here
    let version = crs.geokeys.as_ref().and_then(|(k, _, _)| k.get(..3)).unwrap_or(&[1, 1, 0]);
    let mut out = vec![version[0], version[1], version[2], entries.len() as u16];
    out.extend(entries.iter().flatten());
    out
}

/// Writes `raster` as a single-band 64-bit float GeoTIFF (uncompressed, PixelIsArea, with
/// `GDAL_NODATA` if it has holes): a file that GDAL, QGIS and [`read`] take.
pub fn write(raster: &Raster, path: &Path) -> Result<(), DemError> {
    let file = path.display().to_string();
    let fail = |e: tiff::TiffError| DemError::GeoTiff {
        file: file.clone(),
        problem: format!("cannot write: {e}"),
    };
    let out = File::create(path).map_err(|source| DemError::Io { file: file.clone(), source })?;
    let mut enc = tiff::encoder::TiffEncoder::new(BufWriter::new(out)).map_err(fail)?;
    let [cols, rows] = raster.size();
    let mut image = enc
        .new_image::<tiff::encoder::colortype::Gray64Float>(cols as u32, rows as u32)
        .map_err(fail)?;
    let [west, _, _, north] = raster.extent();
    let c = raster.cell();
    let d = image.encoder();
    d.write_tag(Tag::ModelPixelScaleTag, &[c, c, 0.0][..]).map_err(fail)?;
    d.write_tag(Tag::ModelTiepointTag, &[0.0, 0.0, 0.0, west, north, 0.0][..]).map_err(fail)?;
    // GeoKeyDirectory: the CRS's keys with GTRasterTypeGeoKey = PixelIsArea
    d.write_tag(Tag::GeoKeyDirectoryTag, &directory(raster.crs())[..]).map_err(fail)?;
    if let Some((_, doubles, ascii)) = &raster.crs().geokeys {
        if !doubles.is_empty() {
            d.write_tag(Tag::GeoDoubleParamsTag, &doubles[..]).map_err(fail)?;
        }
        if !ascii.is_empty() {
            d.write_tag(Tag::GeoAsciiParamsTag, ascii.as_str()).map_err(fail)?;
        }
    }
    if let Some(nd) = raster.nodata() {
        d.write_tag(Tag::GdalNodata, format!("{nd:?}").as_str()).map_err(fail)?;
    }
    image.write_data(raster.heights()).map_err(fail)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The keys carried: inline ones and those whose parameters were read; a key into a tag that
    /// could not be read, or into the directory itself, is left out; the version is the source's.
    #[test]
    fn keys_are_carried_only_with_their_parameters() {
        let keys = vec![
            1, 1, 1, 4, //
            1024, 0, 1, 1, // model type: inline
            2049, 34737, 10, 0, // a citation in the ASCII parameters
            2057, 34736, 1, 0, // a semi-major axis in the double parameters
            4096, 34735, 2, 20, // values inside the directory
        ];
        let (k, d, a) =
            carried_keys(keys.clone(), Some(vec![6_378_137.0]), Some("WGS 84 / x|".into()))
                .unwrap();
        assert_eq!(k, [1, 1, 1, 3, 1024, 0, 1, 1, 2049, 34737, 10, 0, 2057, 34736, 1, 0]);
        assert_eq!((d.len(), a.len()), (1, 11));
        // neither parameter tag read (not ASCII, say): the inline key alone
        let (k, _, _) = carried_keys(keys, None, None).unwrap();
        assert_eq!(k, [1, 1, 1, 1, 1024, 0, 1, 1]);
        assert_eq!(carried_keys(vec![1, 1], None, None), None);
        // written: the raster type added in order, the version kept
        let crs = crate::Crs { geokeys: Some((k, Vec::new(), String::new())), wkt: None };
        assert_eq!(directory(&crs), [1, 1, 1, 2, 1024, 0, 1, 1, RASTER_TYPE_KEY, 0, 1, 1]);
    }
}
