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

/// Point-cloud reader limits picked by byte `b`: the default, none, tiny and small.
pub fn max_points(b: u8) -> u64 {
    const LIMITS: [u64; 4] = [
        host_sim::terrain::pointcloud::PointCloudOptions::DEFAULT_MAX_POINTS,
        0,
        1,
        1000,
    ];
    LIMITS[usize::from(b) % LIMITS.len()]
}

/// Fuzzes a point-cloud reader (`host_sim::terrain::pointcloud`): byte 0 picks the point limit, byte 1 the
/// thinning capacity (1 to 64), the rest is the file. An accepted cloud has at least one point, no more than the
/// limit, every coordinate finite; thinning it keeps at most the capacity, every point an input point.
pub fn point_cloud(data: &[u8], parse: host_sim::terrain::pointcloud::Parser) {
    use host_sim::terrain::pointcloud::thin::{thin_to_capacity, ThinOptions};
    tolerate_decoder_panics();
    use host_sim::terrain::pointcloud::PointCloudOptions;
    let Some(([limit, b], bytes)) = split::<2>(data) else {
        return;
    };
    let max_points = max_points(limit);
    let Ok(c) = parse(bytes, &PointCloudOptions { max_points }) else {
        return;
    };
    assert!(!c.points.is_empty(), "empty cloud accepted");
    assert!(
        c.points.len() as u64 <= max_points,
        "{} points over the limit {max_points}",
        c.points.len()
    );
    assert!(
        c.points.iter().flatten().all(|v| v.is_finite()),
        "non-finite coordinate accepted"
    );
    let capacity = usize::from(b % 64) + 1;
    let t = thin_to_capacity(
        &c.points,
        &ThinOptions {
            capacity,
            ..ThinOptions::default()
        },
    )
    .expect("thinning a finite cloud to a positive capacity");
    assert!(
        !t.points.is_empty() && t.points.len() <= capacity,
        "{} points for capacity {capacity}",
        t.points.len()
    );
    assert!(
        t.points.iter().all(|p| c.points.contains(p)),
        "a thinned point is not an input point"
    );
}

/// Source paths of the crates whose panics `host_sim::terrain::pointcloud::las::parse_las` catches and returns
/// as `PointCloudError::DecoderPanic`: the `las` crate and the `laz` decompressor (its arithmetic decoder
/// `debug_assert`s on corrupt data; the fuzz build has debug assertions on).
const DECODER_CRATES: [&str; 2] = ["/las-0.", "/laz-0."];

/// libFuzzer's panic hook aborts on every panic, even one the code under test catches. Replaced once by a hook
/// that lets a panic raised inside [`DECODER_CRATES`] unwind to the reader's `catch_unwind` (the reader's
/// documented error) and hands every other panic, ours included, to libFuzzer's hook, which aborts: a crash.
fn tolerate_decoder_panics() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        let fuzzer_hook = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            let in_decoder = info
                .location()
                .is_some_and(|l| DECODER_CRATES.iter().any(|c| l.file().contains(c)));
            if !in_decoder {
                fuzzer_hook(info);
            }
        }));
    });
}
