//! Helpers shared by the fuzz targets: reader options chosen by the input's first bytes, and the contract every
//! successfully read height map must meet (the readers' docs: `host_sim::terrain`).

use host_sim::terrain::Heightmap;

/// Option values a reader must either accept or reject with an error: ordinary, tiny, huge, zero, negative and
/// non-finite.
const SCALES: [f64; 8] = [1.0, 0.5, 1e-9, 1e300, 0.0, -2.0, f64::NAN, f64::INFINITY];

/// The option value picked by byte `b`.
pub fn scale(b: u8) -> f64 {
    SCALES[usize::from(b) % SCALES.len()]
}

/// Splits off the first `N` bytes (option selectors); `None` when the input is shorter.
pub fn split<const N: usize>(data: &[u8]) -> Option<([u8; N], &[u8])> {
    let (head, rest) = data.split_at_checked(N)?;
    Some((head.try_into().ok()?, rest))
}

/// What an accepted DEM guarantees: a non-empty grid whose heights fill it, a finite positive spacing, and
/// finite heights (missing posts are `None`, never an infinity or NaN).
pub fn check_heightmap(h: &Heightmap) {
    assert!(
        h.width > 0 && h.height > 0,
        "empty grid accepted: {}x{}",
        h.width,
        h.height
    );
    assert_eq!(
        h.heights_m.len(),
        h.width * h.height,
        "heights do not fill the grid"
    );
    assert!(
        h.spacing_m.is_finite() && h.spacing_m > 0.0,
        "spacing {}",
        h.spacing_m
    );
    for (i, z) in h.heights_m.iter().enumerate() {
        if let Some(z) = z {
            assert!(z.is_finite(), "post {i} has height {z}");
        }
    }
}
