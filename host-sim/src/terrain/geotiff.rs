//! GeoTIFF digital elevation models (single band, int16 or float32; also uint8/16, int8/32, float64).
//!
//! - Heights are multiplied by [`GeoTiffOptions::height_scale`] (e.g. 0.5 for the LOLA Kepler crater file, whose
//!   int16 samples are half-metres).
//! - Post spacing comes from `ModelPixelScaleTag` (33550, the x scale) if present, else from
//!   [`GeoTiffOptions::spacing_m`]; a file with neither is rejected. `spacing_m` overrides the tag when set.
//! - "No data" comes from [`GeoTiffOptions::nodata`] if set, else from the `GDAL_NODATA` tag (42113, ASCII) if
//!   present; samples equal to it, and NaN samples, become `None`.
//! - TIFF row 0 is the north edge; [`Heightmap`] row 0 is the south edge, so rows are flipped.

use super::Heightmap;
use std::path::Path;
use tiff::decoder::{Decoder, DecodingResult};
use tiff::tags::Tag;

/// Options for [`load_geotiff`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GeoTiffOptions {
    /// Multiplier from stored sample to metres. Default 1.0.
    pub height_scale: f64,
    /// Post spacing in metres; `None` = take it from `ModelPixelScaleTag`. Default `None`.
    pub spacing_m: Option<f64>,
    /// The stored "no data" value; `None` = take it from `GDAL_NODATA` if present. Default `None`.
    pub nodata: Option<f64>,
}

impl Default for GeoTiffOptions {
    fn default() -> Self {
        GeoTiffOptions { height_scale: 1.0, spacing_m: None, nodata: None }
    }
}

/// Why a GeoTIFF could not be loaded.
#[derive(Debug)]
pub enum GeoTiffError {
    /// The file could not be opened or read.
    Io(std::io::Error),
    /// The TIFF decoder rejected the file.
    Tiff(tiff::TiffError),
    /// The file is a TIFF but not a DEM we can read (the reason says why).
    Unsupported(String),
}

impl core::fmt::Display for GeoTiffError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            GeoTiffError::Io(e) => write!(f, "cannot read file: {e}"),
            GeoTiffError::Tiff(e) => write!(f, "not a readable TIFF: {e}"),
            GeoTiffError::Unsupported(r) => write!(f, "unsupported GeoTIFF: {r}"),
        }
    }
}

impl core::error::Error for GeoTiffError {}

/// Loads a GeoTIFF DEM from a file.
pub fn load_geotiff(path: &Path, opts: &GeoTiffOptions) -> Result<Heightmap, GeoTiffError> {
    let f = std::fs::File::open(path).map_err(GeoTiffError::Io)?;
    read_geotiff(std::io::BufReader::new(f), opts)
}

/// Reads a GeoTIFF DEM from any seekable reader.
pub fn read_geotiff<R: std::io::Read + std::io::Seek>(
    r: R,
    opts: &GeoTiffOptions,
) -> Result<Heightmap, GeoTiffError> {
    if !(opts.height_scale.is_finite() && opts.height_scale != 0.0) {
        return Err(GeoTiffError::Unsupported("height_scale must be finite and non-zero".into()));
    }
    let mut dec = Decoder::new(r).map_err(GeoTiffError::Tiff)?;
    let (w, h) = dec.dimensions().map_err(GeoTiffError::Tiff)?;
    let (width, height) = (w as usize, h as usize);
    let spacing = match opts.spacing_m {
        Some(s) => s,
        None => match dec.find_tag(Tag::ModelPixelScaleTag).map_err(GeoTiffError::Tiff)? {
            Some(v) => {
                let v = v.into_f64_vec().map_err(GeoTiffError::Tiff)?;
                *v.first().ok_or_else(|| GeoTiffError::Unsupported("empty ModelPixelScaleTag".into()))?
            }
            None => {
                return Err(GeoTiffError::Unsupported(
                    "no ModelPixelScaleTag (33550): give the post spacing explicitly".into(),
                ))
            }
        },
    };
    if !(spacing.is_finite() && spacing > 0.0) {
        return Err(GeoTiffError::Unsupported(format!("post spacing {spacing} is not a positive number")));
    }
    let nodata = match opts.nodata {
        Some(n) => Some(n),
        None => match dec.find_tag(Tag::GdalNodata).map_err(GeoTiffError::Tiff)? {
            Some(v) => {
                let s = v.into_string().map_err(GeoTiffError::Tiff)?;
                let s = s.trim_matches(|c: char| c == '\0' || c.is_whitespace());
                Some(s.parse::<f64>().map_err(|_| {
                    GeoTiffError::Unsupported(format!("GDAL_NODATA tag {s:?} is not a number"))
                })?)
            }
            None => None,
        },
    };
    let samples: Vec<f64> = match dec.read_image().map_err(GeoTiffError::Tiff)? {
        DecodingResult::F32(v) => v.into_iter().map(f64::from).collect(),
        DecodingResult::F64(v) => v,
        DecodingResult::I16(v) => v.into_iter().map(f64::from).collect(),
        DecodingResult::U16(v) => v.into_iter().map(f64::from).collect(),
        DecodingResult::I32(v) => v.into_iter().map(f64::from).collect(),
        DecodingResult::U8(v) => v.into_iter().map(f64::from).collect(),
        DecodingResult::I8(v) => v.into_iter().map(f64::from).collect(),
        _ => return Err(GeoTiffError::Unsupported("sample format is not int8/16/32, uint8/16 or float32/64".into())),
    };
    if samples.len() != width * height {
        return Err(GeoTiffError::Unsupported(format!(
            "{} samples for {width} x {height} pixels (more than one band?)",
            samples.len()
        )));
    }
    let mut heights_m = Vec::with_capacity(samples.len());
    for row in (0..height).rev() {
        for (col, s) in samples.iter().skip(row * width).take(width).enumerate() {
            let missing = s.is_nan() || nodata.is_some_and(|n| *s == n);
            if !missing && !(s * opts.height_scale).is_finite() {
                // An infinite height is not "no data" (that is the GDAL_NODATA tag or `nodata`): the file is damaged.
                return Err(GeoTiffError::Unsupported(format!(
                    "pixel (file row {row}, column {col}) is {s} (x height_scale {}): heights must be finite; mark missing \
                     posts with the GDAL_NODATA tag or the scenario's nodata",
                    opts.height_scale
                )));
            }
            heights_m.push(if missing { None } else { Some(s * opts.height_scale) });
        }
    }
    Ok(Heightmap { width, height, spacing_m: spacing, heights_m })
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Cursor;
    use tiff::encoder::{colortype, TiffEncoder};

    /// A 3 x 2 int16 GeoTIFF written in memory with the pixel scale and GDAL_NODATA tags.
    fn fixture_i16(with_tags: bool) -> Vec<u8> {
        let mut buf = Cursor::new(Vec::new());
        {
            let mut enc = TiffEncoder::new(&mut buf).unwrap();
            let mut img = enc.new_image::<colortype::GrayI16>(3, 2).unwrap();
            if with_tags {
                img.encoder().write_tag(Tag::ModelPixelScaleTag, &[2.5f64, 2.5, 0.0][..]).unwrap();
                img.encoder().write_tag(Tag::GdalNodata, "-32768").unwrap();
            }
            // north row first: 1 2 3 / 4 -32768 6
            img.write_data(&[1i16, 2, 3, 4, -32768, 6]).unwrap();
        }
        buf.into_inner()
    }

    #[test]
    fn int16_with_tags_scale_and_nodata() {
        let hm = read_geotiff(Cursor::new(fixture_i16(true)), &GeoTiffOptions { height_scale: 0.5, ..Default::default() })
            .unwrap();
        assert_eq!((hm.width, hm.height, hm.spacing_m), (3, 2, 2.5));
        // row 0 (south) is the file's last row
        assert_eq!(hm.get(0, 0), Some(2.0));
        assert_eq!(hm.get(1, 0), None);
        assert_eq!(hm.get(2, 0), Some(3.0));
        assert_eq!(hm.get(0, 1), Some(0.5));
    }

    #[test]
    fn missing_pixel_scale_is_an_actionable_error() {
        let e = read_geotiff(Cursor::new(fixture_i16(false)), &GeoTiffOptions::default()).unwrap_err();
        assert!(e.to_string().contains("give the post spacing"), "{e}");
        let hm = read_geotiff(Cursor::new(fixture_i16(false)), &GeoTiffOptions { spacing_m: Some(1.0), ..Default::default() })
            .unwrap();
        // without a nodata tag, -32768 is a height
        assert_eq!(hm.get(1, 0), Some(-32768.0));
    }

    /// Regression (issue 24): +inf heights in a float GeoTIFF were accepted (NaN stays "no data").
    #[test]
    fn infinite_heights_are_rejected() {
        let tiff = |data: &[f32]| {
            let mut buf = Cursor::new(Vec::new());
            {
                let mut enc = TiffEncoder::new(&mut buf).unwrap();
                let mut img = enc.new_image::<colortype::Gray32Float>(3, 2).unwrap();
                img.encoder().write_tag(Tag::ModelPixelScaleTag, &[1.0f64, 1.0, 0.0][..]).unwrap();
                img.write_data(data).unwrap();
            }
            buf.into_inner()
        };
        let opts = GeoTiffOptions::default();
        let hm = read_geotiff(Cursor::new(tiff(&[1.0, 2.0, 3.0, 4.0, f32::NAN, 6.0])), &opts).unwrap();
        assert_eq!(hm.get(1, 0), None);
        let e = read_geotiff(Cursor::new(tiff(&[1.0, 2.0, 3.0, 4.0, f32::INFINITY, 6.0])), &opts).unwrap_err();
        assert!(e.to_string().contains("(file row 1, column 1) is inf"), "{e}");
        let big = GeoTiffOptions { height_scale: 1e300, ..Default::default() };
        let e = read_geotiff(Cursor::new(tiff(&[1.0, 2.0, 3.0, 4.0, 5e30, 6.0])), &big).unwrap_err();
        assert!(e.to_string().contains("must be finite"), "{e}");
    }

    #[test]
    fn garbage_is_rejected() {
        assert!(read_geotiff(Cursor::new(b"not a tiff at all".to_vec()), &GeoTiffOptions::default()).is_err());
    }

    #[test]
    fn shared_data_files_load() {
        let base = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/data/terrain");
        let mars = load_geotiff(&base.join("erc_marsyard2021_hm.tif"), &GeoTiffOptions::default()).unwrap();
        assert_eq!((mars.width, mars.height), (500, 500));
        assert!((mars.spacing_m - 0.094).abs() < 0.01, "{}", mars.spacing_m);
        let kepler = load_geotiff(
            &base.join("lola_kepler_crater_orthographic_47m.tif"),
            &GeoTiffOptions { height_scale: 0.5, ..Default::default() },
        )
        .unwrap();
        assert_eq!((kepler.width, kepler.height), (804, 804));
        let (lo, hi) = kepler.heights_m.iter().flatten().fold((f64::MAX, f64::MIN), |(a, b), h| (a.min(*h), b.max(*h)));
        // ~3.2 km of relief (shared/README.md)
        assert!((2500.0..4000.0).contains(&(hi - lo)), "relief {}", hi - lo);
        let pole = load_geotiff(&base.join("lola_ldem256_south_polar_1600m.tif"), &GeoTiffOptions::default()).unwrap();
        assert_eq!((pole.width, pole.height), (762, 762));
    }
}
