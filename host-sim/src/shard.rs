//! Campaigns split over a cluster (issue 23, item 3): the shard a run does, and the checks a merge makes.
//!
//! **The split.** `--shard K/N` (0 <= K < N, N >= 1; default: the whole campaign, `0/1`) runs the trials (planning
//! campaigns) or missions (mission campaigns) whose index `i` has `i mod N == K`. Index `i` keeps its own seed
//! (first seed + i) whatever the split, and every trial or mission is a pure function of its seed, so a result does
//! not depend on the sharding: the merge of the N shards is byte for byte the file the unsharded run writes. `K` is
//! 0-based so that it is a Slurm job array's `SLURM_ARRAY_TASK_ID` (`--array=0-(N-1)`) or a Kubernetes Indexed
//! Job's `JOB_COMPLETION_INDEX` as it is. `N` may not exceed the number of trials or missions (no empty shard).
//!
//! **The merge** reads every shard's file and refuses, naming the files: a file that is not a shard's result
//! (corrupt, truncated, another kind, an unsharded result), shards of different campaigns (the identity differs:
//! scenario, its file's fingerprint, seeds, counts, parameters; each differing field is named with both values),
//! shards split in different ways (N differs), a shard given twice, and missing shards.

use std::path::{Path, PathBuf};

use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};

/// Which part of a campaign a run does: the indices `i` with `i mod count == index`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Shard {
    /// K, 0-based.
    pub index: u32,
    /// N.
    pub count: u32,
}

impl Shard {
    /// The whole campaign (`0/1`).
    pub const WHOLE: Shard = Shard { index: 0, count: 1 };

    /// Whether this is the whole campaign.
    pub fn is_whole(&self) -> bool {
        self.count == 1
    }

    /// Whether index `i` belongs to this shard.
    pub fn holds(&self, i: u64) -> bool {
        i % u64::from(self.count.max(1)) == u64::from(self.index)
    }

    /// The indices below `total` that belong to this shard, in order.
    pub fn indices(&self, total: u32) -> Vec<u32> {
        (0..total).filter(|&i| self.holds(u64::from(i))).collect()
    }

    /// Checks that the split fits `total` items (`what`: "trials", "missions"): no empty shard.
    pub fn check_fits(&self, total: u32, what: &str) -> Result<(), String> {
        if self.count > total {
            return Err(format!(
                "--shard {self}: {} shards for {total} {what} would leave a shard empty; use at most {total} shards",
                self.count
            ));
        }
        Ok(())
    }
}

impl core::fmt::Display for Shard {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

impl core::str::FromStr for Shard {
    type Err = String;

    /// `K/N` with 0 <= K < N.
    fn from_str(s: &str) -> Result<Shard, String> {
        let bad = |why: &str| format!("{s:?}: {why}; write K/N with 0 <= K < N, e.g. 0/4 (K is the 0-based shard index)");
        let (k, n) = s.split_once('/').ok_or_else(|| bad("no '/'"))?;
        let index: u32 = k.trim().parse().map_err(|_| bad("K is not a whole number"))?;
        let count: u32 = n.trim().parse().map_err(|_| bad("N is not a whole number"))?;
        if count == 0 {
            return Err(bad("N must be at least 1"));
        }
        if index >= count {
            return Err(bad("K must be below N"));
        }
        Ok(Shard { index, count })
    }
}

/// A short fingerprint of a scenario file's bytes (CRC-64/XZ, hex): shards of a scenario file that changed between
/// runs are different campaigns.
pub fn fingerprint(bytes: &[u8]) -> String {
    const CRC: crc::Crc<u64> = crc::Crc::<u64>::new(&crc::CRC_64_XZ);
    format!("{:016x}", CRC.checksum(bytes))
}

/// The wall-clock figures of one run (a whole campaign or one shard), in the timing files of both kinds.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunTiming {
    /// The shard (absent: the whole campaign).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shard: Option<Shard>,
    /// Worker threads.
    pub threads: usize,
    /// Seconds of the whole run.
    pub wall_s: f64,
    /// Seconds to build the planning map (planning campaigns only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub map_build_s: Option<f64>,
}

/// One shard's file as read by a merge.
pub struct ShardFile<I, T> {
    /// Where it was read from.
    pub path: PathBuf,
    /// The campaign it belongs to.
    pub identity: I,
    /// Its part of the campaign.
    pub shard: Shard,
    /// The rest of the file.
    pub body: T,
}

/// Reads `path` as JSON of type `F`, naming the file and what it should have been (`what`) in the error.
pub fn read_json<F: DeserializeOwned>(path: &Path, what: &str) -> Result<F, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: cannot read it: {e}", path.display()))?;
    serde_json::from_str(&text)
        .map_err(|e| format!("{}: not {what} (corrupt, truncated or another kind of file): {e}", path.display()))
}

/// The fields in which two identities differ, as `field: a vs b`.
fn differences<I: Serialize>(a: &I, b: &I) -> Vec<String> {
    let (Ok(serde_json::Value::Object(a)), Ok(serde_json::Value::Object(b))) = (serde_json::to_value(a), serde_json::to_value(b))
    else {
        return vec!["(identities not comparable)".into()];
    };
    let mut out = Vec::new();
    for (k, va) in &a {
        let vb = b.get(k).unwrap_or(&serde_json::Value::Null);
        if va != vb {
            out.push(format!("{k}: {va} vs {vb}"));
        }
    }
    out
}

/// Checks that `files` are the N shards of one campaign, each once, and orders them by shard index.
pub fn check_set<I: Serialize + PartialEq, T>(mut files: Vec<ShardFile<I, T>>) -> Result<Vec<ShardFile<I, T>>, String> {
    let Some(first) = files.first() else {
        return Err("no shard files given".into());
    };
    let (p0, n) = (first.path.clone(), first.shard.count);
    for f in &files[1..] {
        if f.identity != first.identity {
            return Err(format!(
                "{} and {} are shards of different campaigns ({}); merge only the shards of one run",
                p0.display(),
                f.path.display(),
                differences(&first.identity, &f.identity).join("; ")
            ));
        }
        if f.shard.count != n {
            return Err(format!(
                "{} is shard {} and {} is shard {}: the campaign was split in two different ways; merge the shards of one split",
                p0.display(),
                first.shard,
                f.path.display(),
                f.shard
            ));
        }
    }
    files.sort_by_key(|f| f.shard.index);
    for w in files.windows(2) {
        if w[0].shard.index == w[1].shard.index {
            return Err(format!("shard {} is given twice: {} and {}", w[0].shard, w[0].path.display(), w[1].path.display()));
        }
    }
    let have: Vec<u32> = files.iter().map(|f| f.shard.index).collect();
    let missing: Vec<String> = (0..n).filter(|k| !have.contains(k)).map(|k| format!("{k}/{n}")).collect();
    if !missing.is_empty() {
        return Err(format!(
            "missing shard(s) {} of the {n}: a merge needs every shard's file (run the missing shards, then merge again)",
            missing.join(", ")
        ));
    }
    Ok(files)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parse_accepts_k_below_n_and_says_what_is_wrong_otherwise() {
        assert_eq!("3/4".parse::<Shard>(), Ok(Shard { index: 3, count: 4 }));
        assert_eq!("0/1".parse::<Shard>(), Ok(Shard::WHOLE));
        for (bad, why) in [("4/4", "K must be below N"), ("0/0", "N must be at least 1"), ("1", "no '/'"), ("a/2", "K is not"), ("-1/2", "K is not")] {
            let e = bad.parse::<Shard>().expect_err(bad);
            assert!(e.contains(why), "{bad}: {e}");
        }
    }

    #[test]
    fn the_shards_of_a_split_partition_the_indices() {
        let n = 4;
        let mut seen = vec![0u32; 11];
        for k in 0..n {
            for i in (Shard { index: k, count: n }).indices(11) {
                assert_eq!(i % n, k);
                seen[i as usize] += 1;
            }
        }
        assert!(seen.iter().all(|&c| c == 1), "{seen:?}");
        assert!(Shard { index: 0, count: 5 }.check_fits(4, "trials").is_err());
        assert!(Shard { index: 0, count: 4 }.check_fits(4, "trials").is_ok());
    }

    /// Regression (ledge test 3, 8 trials in 4 shards, release): without serde_json's `float_roundtrip` the merge
    /// read -0.11706714332103729 as ...728 and wrote a results.json 1 ULP off the unsharded run's.
    #[test]
    fn every_finite_f64_survives_a_json_round_trip_to_the_bit() {
        use rand_core::{Rng, SeedableRng};
        let mut rng = rand_pcg::Pcg64::seed_from_u64(23);
        let mut xs = vec![-0.11706714332103729, 0.19527274370193481, 0.24475063383579254, 5e-324, f64::MAX, -0.0];
        xs.extend((0..200_000).map(|_| f64::from_bits(rng.next_u64())).filter(|x| x.is_finite()));
        xs.extend((0..200_000).map(|_| (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64 * 20.0 - 10.0));
        for x in xs {
            let text = serde_json::to_string(&x).expect("finite");
            let back: f64 = serde_json::from_str(&text).expect("parses");
            assert_eq!(back.to_bits(), x.to_bits(), "{text}");
        }
    }

    fn file(path: &str, id: u32, k: u32, n: u32) -> ShardFile<serde_json::Value, ()> {
        ShardFile { path: path.into(), identity: serde_json::json!({ "trials": id }), shard: Shard { index: k, count: n }, body: () }
    }

    #[test]
    fn check_set_names_missing_duplicate_and_foreign_shards() {
        let ok = check_set(vec![file("b", 8, 1, 2), file("a", 8, 0, 2)]).expect("complete");
        assert_eq!(ok.iter().map(|f| f.shard.index).collect::<Vec<_>>(), [0, 1]);
        let e = check_set(vec![file("a", 8, 0, 3), file("c", 8, 2, 3)]).err().unwrap_or_default();
        assert!(e.contains("missing shard(s) 1/3"), "{e}");
        let e = check_set(vec![file("a", 8, 0, 2), file("b", 8, 0, 2)]).err().unwrap_or_default();
        assert!(e.contains("shard 0/2 is given twice: a and b"), "{e}");
        let e = check_set(vec![file("a", 8, 0, 2), file("b", 6, 1, 2)]).err().unwrap_or_default();
        assert!(e.contains("different campaigns (trials: 8 vs 6)"), "{e}");
        let e = check_set(vec![file("a", 8, 0, 2), file("b", 8, 1, 4)]).err().unwrap_or_default();
        assert!(e.contains("split in two different ways"), "{e}");
    }
}
