//! Moving AI grid benchmark files (N. Sturtevant, "Benchmarks for Grid-Based Pathfinding", IEEE TCIAIG 2012) and
//! a runner that puts every scenario through the team's global planner ([`firmware::plan::team::dstar_lite`]).
//!
//! `.map`: `type octile`, `height H`, `width W`, `map`, then H rows of W characters. `.`, `G`, `S` are passable;
//! `@`, `O`, `T`, `W` are not (any other character is an error). `.scen`: `version 1` (or `version 1.0`), then one
//! line per problem, tab or space separated: bucket, map name, map width, map height, start x, start y, goal x,
//! goal y, optimal length. x is the column, y the row (row 0 is the first map row). Optimal lengths are octile
//! (straight 1, diagonal sqrt 2) with no corner cutting.

use core::fmt;
use firmware::plan::status::Status;
use firmware::plan::team::dstar_lite::{Cost, DStarLite, DStarStorage, Found, Key, NoPath};
use std::path::Path;

/// A parsed `.map`.
#[derive(Debug, Clone, PartialEq)]
pub struct GridMap {
    /// Columns.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// `true` = passable, row-major from the first map row.
    pub passable: Vec<bool>,
}

impl GridMap {
    /// Is (x, y) inside and passable.
    pub fn is_passable(&self, x: usize, y: usize) -> bool {
        x < self.width && y < self.height && self.passable.get(y * self.width + x).copied().unwrap_or(false)
    }
}

/// One `.scen` problem.
#[derive(Debug, Clone, PartialEq)]
pub struct Scenario {
    /// 1-based line number in the file.
    pub line: usize,
    /// Bucket (difficulty group).
    pub bucket: u32,
    /// Map file name as written.
    pub map: String,
    /// Start column.
    pub start_x: usize,
    /// Start row.
    pub start_y: usize,
    /// Goal column.
    pub goal_x: usize,
    /// Goal row.
    pub goal_y: usize,
    /// Published optimal octile length.
    pub optimal: f64,
    /// Decimal places the optimal length was printed with (its precision).
    pub decimals: usize,
}

/// Why a Moving AI file could not be read.
#[derive(Debug)]
pub enum MovingAiError {
    /// File could not be read.
    Io(std::io::Error),
    /// A header line is missing or wrong; the string says what was expected.
    BadHeader {
        /// 1-based line number.
        line: usize,
        /// What was expected.
        expected: &'static str,
    },
    /// A map row has the wrong length or a character outside the legend.
    BadRow {
        /// 1-based line number.
        line: usize,
        /// Why.
        reason: String,
    },
    /// Fewer map rows than the header announced.
    MissingRows {
        /// Rows announced.
        expected: usize,
        /// Rows found.
        found: usize,
    },
    /// A scenario line that does not have nine well-formed fields.
    BadScenario {
        /// 1-based line number.
        line: usize,
        /// Why.
        reason: String,
    },
}

impl fmt::Display for MovingAiError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            MovingAiError::Io(e) => write!(f, "cannot read Moving AI file: {e}"),
            MovingAiError::BadHeader { line, expected } => write!(f, "line {line}: expected {expected}"),
            MovingAiError::BadRow { line, reason } => write!(f, "map line {line}: {reason}"),
            MovingAiError::MissingRows { expected, found } => {
                write!(f, "map has {found} rows, header says {expected}")
            }
            MovingAiError::BadScenario { line, reason } => write!(f, "scenario line {line}: {reason}"),
        }
    }
}

impl core::error::Error for MovingAiError {}

impl From<std::io::Error> for MovingAiError {
    fn from(e: std::io::Error) -> Self {
        MovingAiError::Io(e)
    }
}

fn header_value(line: Option<(usize, &str)>, key: &'static str, expected: &'static str) -> Result<usize, MovingAiError> {
    let (n, text) = line.ok_or(MovingAiError::BadHeader { line: 0, expected })?;
    let mut it = text.split_whitespace();
    if it.next() != Some(key) {
        return Err(MovingAiError::BadHeader { line: n, expected });
    }
    let v = it.next().and_then(|s| s.parse::<usize>().ok()).filter(|&v| v > 0);
    v.ok_or(MovingAiError::BadHeader { line: n, expected })
}

/// Parse `.map` text.
pub fn parse_map(text: &str) -> Result<GridMap, MovingAiError> {
    let mut lines = text.lines().enumerate().map(|(i, l)| (i + 1, l.trim_end_matches('\r')));
    let (n, t) = lines.next().ok_or(MovingAiError::BadHeader { line: 1, expected: "`type octile`" })?;
    if t.split_whitespace().collect::<Vec<_>>() != ["type", "octile"] {
        return Err(MovingAiError::BadHeader { line: n, expected: "`type octile`" });
    }
    let height = header_value(lines.next(), "height", "`height H` with H > 0")?;
    let width = header_value(lines.next(), "width", "`width W` with W > 0")?;
    let (n, t) = lines.next().ok_or(MovingAiError::BadHeader { line: 4, expected: "`map`" })?;
    if t.trim() != "map" {
        return Err(MovingAiError::BadHeader { line: n, expected: "`map`" });
    }
    let cells = width
        .checked_mul(height)
        .filter(|&c| c <= 1 << 28)
        .ok_or(MovingAiError::BadHeader { line: 3, expected: "a map of at most 2^28 cells" })?;
    let mut passable = Vec::with_capacity(cells);
    let mut rows = 0;
    for (n, row) in lines {
        if rows == height {
            if row.trim().is_empty() {
                continue;
            }
            return Err(MovingAiError::BadRow { line: n, reason: format!("more than {height} rows") });
        }
        let chars = row.as_bytes();
        if chars.len() != width {
            return Err(MovingAiError::BadRow { line: n, reason: format!("{} characters, expected {width}", chars.len()) });
        }
        for &c in chars {
            passable.push(match c {
                b'.' | b'G' | b'S' => true,
                b'@' | b'O' | b'T' | b'W' => false,
                other => {
                    return Err(MovingAiError::BadRow {
                        line: n,
                        reason: format!("character {:?} is not in the legend (. G S @ O T W)", other as char),
                    })
                }
            });
        }
        rows += 1;
    }
    if rows != height {
        return Err(MovingAiError::MissingRows { expected: height, found: rows });
    }
    Ok(GridMap { width, height, passable })
}

/// Parse `.scen` text. A cut file is an error, not fewer scenarios: the text must end with a newline (Moving AI's
/// files do; a file cut inside its last line does not), every optimal length must have as many decimals as the
/// first (a cut inside the last number shortens it), and there must be at least one scenario. A cut exactly at a
/// line boundary cannot be told from a shorter file (the format has no count).
pub fn parse_scen(text: &str) -> Result<Vec<Scenario>, MovingAiError> {
    let mut out: Vec<Scenario> = Vec::new();
    let last_line = text.lines().count().max(1);
    if !text.is_empty() && !text.ends_with('\n') {
        return Err(MovingAiError::BadScenario {
            line: last_line,
            reason: "the file does not end with a newline: truncated inside this line?".into(),
        });
    }
    let mut lines = text.lines().enumerate().map(|(i, l)| (i + 1, l.trim_end_matches('\r')));
    let (n, first) = lines.next().ok_or(MovingAiError::BadHeader { line: 1, expected: "`version 1`" })?;
    let v: Vec<&str> = first.split_whitespace().collect();
    if v.len() != 2 || v[0] != "version" || !v[1].starts_with('1') {
        return Err(MovingAiError::BadHeader { line: n, expected: "`version 1`" });
    }
    for (n, line) in lines {
        if line.trim().is_empty() {
            continue;
        }
        let f: Vec<&str> = line.split(['\t', ' ']).filter(|s| !s.is_empty()).collect();
        let bad = |reason: &str| MovingAiError::BadScenario { line: n, reason: reason.to_string() };
        if f.len() != 9 {
            return Err(bad(&format!("{} fields, expected 9", f.len())));
        }
        let num = |i: usize, what: &str| f[i].parse::<usize>().map_err(|_| bad(&format!("{what} {:?} is not a whole number", f[i])));
        let optimal: f64 = f[8].parse().map_err(|_| bad("optimal length is not a number"))?;
        if !(optimal.is_finite() && optimal >= 0.0) {
            return Err(bad("optimal length must be finite and >= 0"));
        }
        let decimals = f[8].split_once('.').map(|(_, d)| d.len()).unwrap_or(0);
        if let Some(first) = out.first() {
            if first.decimals != decimals {
                return Err(bad(&format!(
                    "optimal length {:?} has {decimals} decimals, line {}'s has {}: truncated?",
                    f[8], first.line, first.decimals
                )));
            }
        }
        out.push(Scenario {
            line: n,
            bucket: num(0, "bucket")? as u32,
            map: f[1].to_string(),
            start_x: num(4, "start x")?,
            start_y: num(5, "start y")?,
            goal_x: num(6, "goal x")?,
            goal_y: num(7, "goal y")?,
            optimal,
            decimals,
        });
        let _ = (num(2, "map width")?, num(3, "map height")?);
    }
    if out.is_empty() {
        return Err(MovingAiError::BadScenario { line: last_line, reason: "no scenarios after the version line".into() });
    }
    Ok(out)
}

/// Read and parse a `.map` file.
pub fn load_map(path: &Path) -> Result<GridMap, MovingAiError> {
    parse_map(&std::fs::read_to_string(path)?)
}

/// Read and parse a `.scen` file.
pub fn load_scen(path: &Path) -> Result<Vec<Scenario>, MovingAiError> {
    parse_scen(&std::fs::read_to_string(path)?)
}

/// Heap-owned storage for [`DStarLite`] on the host.
pub struct OwnedDStarStorage {
    g: Vec<Cost>,
    rhs: Vec<Cost>,
    stamp: Vec<u32>,
    key: Vec<Key>,
    heap_pos: Vec<u32>,
    heap: Vec<u32>,
    blocked: Vec<bool>,
    walls: Vec<u8>,
    moves: Vec<u8>,
}

impl OwnedDStarStorage {
    /// Storage for `cells` cells.
    pub fn new(cells: usize) -> Self {
        Self {
            g: vec![Cost::INF; cells],
            rhs: vec![Cost::INF; cells],
            stamp: vec![0; cells],
            key: vec![(Cost::ZERO, Cost::ZERO); cells],
            heap_pos: vec![0; cells],
            heap: vec![0; cells],
            blocked: vec![false; cells],
            walls: vec![0; cells],
            moves: vec![0; cells],
        }
    }

    /// Lend it.
    pub fn storage(&mut self) -> DStarStorage<'_> {
        DStarStorage {
            g: &mut self.g,
            rhs: &mut self.rhs,
            stamp: &mut self.stamp,
            key: &mut self.key,
            heap_pos: &mut self.heap_pos,
            heap: &mut self.heap,
            blocked: &mut self.blocked,
            walls: &mut self.walls,
            moves: &mut self.moves,
        }
    }
}

/// A scenario whose planned cost differs from the published optimum.
#[derive(Debug, Clone, PartialEq)]
pub struct Mismatch {
    /// The scenario.
    pub scenario: Scenario,
    /// What D* Lite returned (`None` = no path / budget).
    pub planned: Option<f64>,
}

/// Outcome of a scenario run.
#[derive(Debug, Clone, PartialEq)]
pub struct RunSummary {
    /// Scenarios run.
    pub run: usize,
    /// Mismatches (beyond the tolerance).
    pub mismatches: Vec<Mismatch>,
    /// Total vertices expanded.
    pub expansions: u64,
    /// Largest |planned - optimal| over matched scenarios.
    pub max_abs_error: f64,
}

/// Tolerance for comparing to a published length printed with `decimals` places: half a unit of the last place
/// plus 1e-9, but never looser than 1e-6... unless the file printed fewer than six places.
pub fn tolerance(decimals: usize) -> f64 {
    let printed = 0.5 * 10f64.powi(-(decimals.min(15) as i32)) + 1e-9;
    printed.max(1e-6)
}

/// Plan every scenario (from scratch) with D* Lite on `map` and compare to the published optimum.
/// `filter` picks which scenarios to run (by position in `scens`).
pub fn run_scenarios(map: &GridMap, scens: &[Scenario], mut filter: impl FnMut(usize, &Scenario) -> bool) -> Result<RunSummary, String> {
    let cells = map.width * map.height;
    let mut store = OwnedDStarStorage::new(cells);
    let mut d = DStarLite::new(map.width as u32, map.height as u32, store.storage()).map_err(|e| format!("{e:?}"))?;
    for y in 0..map.height {
        for x in 0..map.width {
            if !map.is_passable(x, y) {
                d.set_blocked(x as i64, y as i64, true).map_err(|e| format!("{e:?}"))?;
            }
        }
    }
    let budget = u32::try_from(cells.saturating_mul(8)).unwrap_or(u32::MAX);
    let mut summary = RunSummary { run: 0, mismatches: Vec::new(), expansions: 0, max_abs_error: 0.0 };
    for (i, s) in scens.iter().enumerate() {
        if !filter(i, s) {
            continue;
        }
        summary.run += 1;
        let out = d
            .plan((s.start_x as i64, s.start_y as i64), (s.goal_x as i64, s.goal_y as i64), budget)
            .map_err(|e| format!("scenario line {}: {e:?}", s.line))?;
        let planned = match out {
            Status::Exact(Found { cost, expansions }) => {
                summary.expansions += expansions as u64;
                Some(cost)
            }
            Status::NoSolution(NoPath { expansions, .. }) => {
                summary.expansions += expansions as u64;
                None
            }
        };
        summary.record(s, planned);
    }
    Ok(summary)
}

impl RunSummary {
    /// Compares a planned cost (`None`: no path) with the scenario's published optimum.
    fn record(&mut self, s: &Scenario, planned: Option<f64>) {
        match planned {
            Some(c) if (c - s.optimal).abs() <= tolerance(s.decimals) => {
                self.max_abs_error = self.max_abs_error.max((c - s.optimal).abs());
            }
            _ => self.mismatches.push(Mismatch { scenario: s.clone(), planned }),
        }
    }
}

/// Fixed-point unit of [`run_astar_reference`]'s path costs: 1e9 per straight step (the `pathfinding` crate wants
/// integer costs; a diagonal step is `sqrt 2` rounded to 1e-9, so a 10,000-step path errs by at most 5e-6).
#[cfg(feature = "sim")]
const ASTAR_UNIT: f64 = 1e9;

/// The same scenarios through the `pathfinding` crate's A* (octile heuristic, no corner cutting: a diagonal step
/// needs both cardinal cells it passes free, as Moving AI's optima assume): the reference D* Lite is compared with
/// and timed against. `expansions` counts the vertices whose successors A* asked for.
#[cfg(feature = "sim")]
pub fn run_astar_reference(map: &GridMap, scens: &[Scenario], mut filter: impl FnMut(usize, &Scenario) -> bool) -> RunSummary {
    let straight = ASTAR_UNIT as u64;
    let diagonal = (core::f64::consts::SQRT_2 * ASTAR_UNIT).round() as u64;
    let free = |x: i64, y: i64| x >= 0 && y >= 0 && map.is_passable(x as usize, y as usize);
    let mut summary = RunSummary { run: 0, mismatches: Vec::new(), expansions: 0, max_abs_error: 0.0 };
    for (i, s) in scens.iter().enumerate() {
        if !filter(i, s) {
            continue;
        }
        summary.run += 1;
        let goal = (s.goal_x as i64, s.goal_y as i64);
        let mut expansions = 0u64;
        let found = pathfinding::prelude::astar(
            &(s.start_x as i64, s.start_y as i64),
            |&(x, y)| {
                expansions += 1;
                // on the stack: the reference is timed, an allocation per expansion would slow it
                let mut next = [((0i64, 0i64), 0u64); 8];
                let mut n = 0;
                for dy in -1..=1i64 {
                    for dx in -1..=1i64 {
                        let ok = (dx, dy) != (0, 0)
                            && free(x + dx, y + dy)
                            && (dx == 0 || dy == 0 || (free(x + dx, y) && free(x, y + dy)));
                        if ok {
                            next[n] = ((x + dx, y + dy), if dx != 0 && dy != 0 { diagonal } else { straight });
                            n += 1;
                        }
                    }
                }
                next.into_iter().take(n)
            },
            |&(x, y)| {
                let (ax, ay) = ((x - goal.0).unsigned_abs(), (y - goal.1).unsigned_abs());
                let (lo, hi) = (ax.min(ay), ax.max(ay));
                lo * diagonal + (hi - lo) * straight
            },
            |&p| p == goal,
        );
        summary.expansions += expansions;
        summary.record(s, found.map(|(_, c)| c as f64 / ASTAR_UNIT));
    }
    summary
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parse_small_map_and_scen() {
        let m = parse_map("type octile\nheight 2\nwidth 3\nmap\n.@G\nTS.\n").unwrap();
        assert_eq!((m.width, m.height), (3, 2));
        assert_eq!(m.passable, vec![true, false, true, false, true, true]);
        let s = parse_scen("version 1\n0\tm.map\t3\t2\t0\t0\t2\t1\t2.41421356\n").unwrap();
        assert_eq!(s.len(), 1);
        assert_eq!((s[0].start_x, s[0].goal_x, s[0].goal_y, s[0].decimals), (0, 2, 1, 8));
    }

    #[test]
    fn bad_files_are_typed() {
        assert!(matches!(parse_map("type tile\n"), Err(MovingAiError::BadHeader { line: 1, .. })));
        assert!(matches!(parse_map("type octile\nheight x\n"), Err(MovingAiError::BadHeader { line: 2, .. })));
        assert!(matches!(parse_map("type octile\nheight 1\nwidth 2\nmap\n.\n"), Err(MovingAiError::BadRow { line: 5, .. })));
        assert!(matches!(parse_map("type octile\nheight 1\nwidth 2\nmap\n.x\n"), Err(MovingAiError::BadRow { .. })));
        assert!(matches!(parse_map("type octile\nheight 2\nwidth 2\nmap\n..\n"), Err(MovingAiError::MissingRows { .. })));
        assert!(matches!(parse_scen("vers 1\n"), Err(MovingAiError::BadHeader { .. })));
        assert!(matches!(parse_scen("version 1\n0 m 3 2 0 0 2\n"), Err(MovingAiError::BadScenario { line: 2, .. })));
        assert!(matches!(parse_scen("version 1\n0 m 3 2 0 -1 2 1 2.0\n"), Err(MovingAiError::BadScenario { .. })));
        assert!(matches!(parse_scen("version 1\n0 m 3 2 0 0 2 1 nan\n"), Err(MovingAiError::BadScenario { .. })));
        // regression (issue 24): a truncated .scen ran its whole scenarios and exited 0
        let two = "version 1\n0 m 3 2 0 0 2 1 2.00000000\n0 m 3 2 0 1 2 1 2.41421356\n";
        assert_eq!(parse_scen(two).map(|v| v.len()).ok(), Some(2));
        for cut in two.find("2.4").unwrap()..two.len() - 1 {
            let e = parse_scen(&two[..cut]).unwrap_err().to_string();
            assert!(e.contains("line 3") && e.contains("truncated"), "cut {cut}: {e}");
        }
        assert!(parse_scen("version 1\n").unwrap_err().to_string().contains("no scenarios"));
    }

    #[test]
    fn damaged_files_never_panic() {
        let map = "type octile\nheight 3\nwidth 3\nmap\n.@.\n...\nT..\n";
        let scen = "version 1\n0\tm.map\t3\t3\t0\t0\t2\t2\t2.82842712\n";
        for text in [map, scen] {
            let b = text.as_bytes();
            for n in 0..b.len() {
                let t = String::from_utf8_lossy(&b[..n]);
                let _ = parse_map(&t);
                let _ = parse_scen(&t);
            }
            for i in 0..b.len() {
                let mut c = b.to_vec();
                c[i] = b"x9 \n\t.@-"[i % 8];
                let t = String::from_utf8_lossy(&c);
                let _ = parse_map(&t);
                let _ = parse_scen(&t);
            }
        }
        // a scenario outside the map is a typed error from the planner, not a panic
        let m = parse_map(map).unwrap();
        let s = parse_scen("version 1\n0 m 3 3 0 0 9 9 1.0\n").unwrap();
        assert!(run_scenarios(&m, &s, |_, _| true).is_err());
    }

    #[test]
    fn corner_cutting_is_forbidden() {
        // . @      diagonal (0,1)->(1,0) would cut the corner of the wall at (1,1)... here both side cells matter
        // . .
        let m = parse_map("type octile\nheight 2\nwidth 2\nmap\n.@\n..\n").unwrap();
        let s = parse_scen("version 1\n0 m 2 2 0 0 1 1 1.41421356\n0 m 2 2 1 1 0 0 1.41421356\n").unwrap();
        // (0,0)->(1,1): side cells (1,0) blocked -> must go around: cost 2
        let r = run_scenarios(&m, &s, |_, _| true).unwrap();
        assert_eq!(r.run, 2);
        assert_eq!(r.mismatches.len(), 2);
        assert_eq!(r.mismatches[0].planned, Some(2.0));
    }
}
