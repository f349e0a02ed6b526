//! The clip list of a batch: BVH and AMC files found recursively (sorted,
//! so every machine sees the same list), split into shards, and each clip's
//! output path in the mirrored tree.

use std::path::{Path, PathBuf};

/// Output format of a batch.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
pub enum Format {
    /// Binary glTF with one morph target per frame.
    Glb,
    /// PC2 point cache with its topology OBJ beside it.
    Pc2,
    /// A folder of OBJ frames.
    Obj,
}

/// One shard `index` of `count` (1-based, as Slurm array indices are
/// usually written): clip k (in sorted order) belongs to shard
/// `k mod count + 1`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shard {
    /// Which shard, 1..=count.
    pub index: usize,
    /// How many shards.
    pub count: usize,
}

impl Shard {
    /// Parses `i/n` with 1 ≤ i ≤ n.
    pub fn parse(s: &str) -> Result<Shard, String> {
        let (i, n) = s
            .split_once('/')
            .ok_or_else(|| format!("--shard {s:?}: expected i/n, e.g. 2/8"))?;
        let (i, n): (usize, usize) = match (i.trim().parse(), n.trim().parse()) {
            (Ok(i), Ok(n)) => (i, n),
            _ => return Err(format!("--shard {s:?}: expected two whole numbers i/n")),
        };
        if n == 0 || i == 0 || i > n {
            return Err(format!("--shard {s:?}: need 1 ≤ i ≤ n"));
        }
        Ok(Shard { index: i, count: n })
    }

    /// The clips of this shard.
    pub fn select<T: Clone>(&self, all: &[T]) -> Vec<T> {
        all.iter()
            .enumerate()
            .filter(|(k, _)| k % self.count + 1 == self.index)
            .map(|(_, c)| c.clone())
            .collect()
    }
}

/// Every `.bvh` and `.amc` file under `dir` (any case), as paths relative
/// to `dir`, sorted. Unreadable folders are skipped.
pub fn find_clips(dir: &Path) -> std::io::Result<Vec<PathBuf>> {
    std::fs::read_dir(dir)?;
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        let Ok(rd) = std::fs::read_dir(&d) else {
            continue;
        };
        for e in rd.flatten() {
            let p = e.path();
            if p.is_dir() {
                stack.push(p);
            } else if p
                .extension()
                .and_then(|x| x.to_str())
                .is_some_and(|x| x.eq_ignore_ascii_case("bvh") || x.eq_ignore_ascii_case("amc"))
                && let Ok(rel) = p.strip_prefix(dir)
            {
                out.push(rel.to_path_buf());
            }
        }
    }
    out.sort();
    Ok(out)
}

/// Where clip `rel` goes under `out_dir`: the same folders, the clip's
/// name with the format's extension (a folder for OBJ frames).
pub fn output_path(out_dir: &Path, rel: &Path, format: Format) -> PathBuf {
    let stem = out_dir.join(rel);
    match format {
        Format::Glb => stem.with_extension("glb"),
        Format::Pc2 => stem.with_extension("pc2"),
        Format::Obj => stem.with_extension(""),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shards_cover_the_list_once() {
        let all: Vec<usize> = (0..10).collect();
        let mut seen = Vec::new();
        for i in 1..=3 {
            seen.extend(Shard::parse(&format!("{i}/3")).unwrap().select(&all));
        }
        seen.sort();
        assert_eq!(seen, all);
        assert!(Shard::parse("0/3").is_err());
        assert!(Shard::parse("4/3").is_err());
        assert!(Shard::parse("a/b").is_err());
        assert!(Shard::parse("3").is_err());
    }

    #[test]
    fn outputs_mirror_the_tree() {
        let p = output_path(Path::new("out"), Path::new("02/02_01.amc"), Format::Glb);
        assert_eq!(p, Path::new("out/02/02_01.glb"));
        let p = output_path(Path::new("out"), Path::new("a.bvh"), Format::Obj);
        assert_eq!(p, Path::new("out/a"));
    }
}
