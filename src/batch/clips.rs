//! The clip list of a batch: BVH and AMC files found recursively (sorted,
//! so every machine sees the same list), split into shards, and each clip's
//! output path in the mirrored tree.

use std::collections::{BTreeMap, HashMap, HashSet};
use std::path::{Path, PathBuf};

/// Output format of a batch.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum Format {
    /// Binary glTF with one morph target per frame.
    Glb,
    /// PC2 point cache with its topology OBJ beside it.
    Pc2,
    /// A folder of OBJ frames.
    Obj,
    /// USD text layer, time-sampled points (`mesh::io::usd`).
    Usda,
}

/// One shard `index` of `count` (1-based): a clip belongs to shard
/// `h mod count + 1`, where `h` is [`clip_hash`] of its path relative to
/// the mocap folder. The split depends on each clip's own path only, so
/// adding clips to a library never moves a clip already converted to
/// another shard (the sorted-list split `k mod count` did: every clip
/// after a new one moved); shards are balanced only on average.
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
            .ok_or_else(|| format!("`BatchOptions::shard` {s:?}: expected i/n, e.g. 2/8"))?;
        let (i, n): (usize, usize) = match (i.trim().parse(), n.trim().parse()) {
            (Ok(i), Ok(n)) => (i, n),
            _ => {
                return Err(format!(
                    "`BatchOptions::shard` {s:?}: expected two whole numbers i/n"
                ));
            }
        };
        if n == 0 || i == 0 || i > n {
            return Err(format!("`BatchOptions::shard` {s:?}: need 1 ≤ i ≤ n"));
        }
        Ok(Shard { index: i, count: n })
    }

    /// True when the clip `rel` (relative to the mocap folder) belongs to
    /// this shard.
    pub fn contains(&self, rel: &Path) -> bool {
        shard_of(rel, self.count) == self.index
    }

    /// The planned clips of this shard, in their order.
    pub fn select(&self, all: &[Planned]) -> Vec<Planned> {
        all.iter()
            .filter(|p| self.contains(&p.clip))
            .cloned()
            .collect()
    }

    /// `i/n`, as [`Shard::parse`] reads it (and `batch-iofn` names files).
    pub fn spelled(&self) -> String {
        format!("{}/{}", self.index, self.count)
    }
}

/// A stable 64-bit hash of a clip's path relative to the mocap folder: FNV-1a
/// over its components joined by `/` (so `a/./b` and `a//b` are `a/b`),
/// finished by the SplitMix64 mixer so that `h mod n` is even for any `n`.
/// The same on every machine, build and run; pinned by a test.
pub fn clip_hash(rel: &Path) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    let mut feed = |b: u8| {
        h ^= u64::from(b);
        h = h.wrapping_mul(0x0000_0100_0000_01b3);
    };
    let mut first = true;
    for c in rel.components() {
        let std::path::Component::Normal(c) = c else {
            continue;
        };
        if !first {
            feed(b'/');
        }
        first = false;
        for &b in c.as_encoded_bytes() {
            feed(b);
        }
    }
    let mut z = h.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// The shard (1..=count) of the clip `rel` in a split of `count`.
pub fn shard_of(rel: &Path, count: usize) -> usize {
    (clip_hash(rel) % count.max(1) as u64) as usize + 1
}

/// Every `.bvh`, `.amc` and `.fbx` file under `dir` (any case), as paths relative
/// to `dir`, sorted. Unreadable folders are skipped. Symbolic links are
/// followed, but every folder is entered once and every clip listed once
/// (by its canonical path), so a link back up the tree neither loops nor
/// converts a clip many times. The real tree is walked before any linked
/// folder, and a clip's own spelling wins over one through a link.
pub fn find_clips(dir: &Path) -> std::io::Result<Vec<PathBuf>> {
    std::fs::read_dir(dir)?;
    // (relative path, canonical path, reached through a link)
    let mut found: Vec<(PathBuf, PathBuf, bool)> = Vec::new();
    let mut seen_dirs = HashSet::new();
    let mut todo: Vec<(PathBuf, bool)> = vec![(PathBuf::new(), false)];
    let mut linked: Vec<(PathBuf, bool)> = Vec::new();
    while !todo.is_empty() || !linked.is_empty() {
        if todo.is_empty() {
            // Folders reached through links, after everything real.
            linked.sort();
            linked.reverse();
            todo.append(&mut linked);
        }
        let Some((rel, via_link)) = todo.pop() else {
            break;
        };
        let here = dir.join(&rel);
        let Ok(canonical) = here.canonicalize() else {
            continue;
        };
        if !seen_dirs.insert(canonical) {
            continue;
        }
        let Ok(rd) = std::fs::read_dir(&here) else {
            continue;
        };
        let mut entries: Vec<_> = rd.flatten().collect();
        entries.sort_by_key(|e| std::cmp::Reverse(e.file_name()));
        for e in entries {
            let r = rel.join(e.file_name());
            let p = dir.join(&r);
            let link = e.file_type().is_ok_and(|t| t.is_symlink());
            // Follows links; a dangling link is skipped.
            let Ok(meta) = std::fs::metadata(&p) else {
                continue;
            };
            if meta.is_dir() {
                if link {
                    linked.push((r, true));
                } else {
                    todo.push((r, via_link));
                }
            } else if is_clip(&p)
                && let Ok(c) = p.canonicalize()
            {
                found.push((r, c, via_link || link));
            }
        }
    }
    // One spelling per clip: its own before any through a link, then the
    // first in sorted order.
    found.sort_by(|a, b| (a.2, &a.0).cmp(&(b.2, &b.0)));
    let mut seen_files = HashSet::new();
    let mut out: Vec<PathBuf> = found
        .into_iter()
        .filter(|(_, canonical, _)| seen_files.insert(canonical.clone()))
        .map(|(rel, _, _)| rel)
        .collect();
    out.sort();
    Ok(out)
}

fn is_clip(p: &Path) -> bool {
    p.extension().and_then(|x| x.to_str()).is_some_and(|x| {
        ["bvh", "amc", "fbx"]
            .iter()
            .any(|e| x.eq_ignore_ascii_case(e))
    })
}

/// Where clip `rel` goes under `out_dir`: the same folders, the clip's
/// name with the format's extension (a folder for OBJ frames).
pub fn output_path(out_dir: &Path, rel: &Path, format: Format) -> PathBuf {
    with_format(out_dir.join(rel).with_extension(""), format)
}

fn with_format(stem: PathBuf, format: Format) -> PathBuf {
    let name = |ext: &str| {
        let mut n = stem.file_name().unwrap_or_default().to_os_string();
        n.push(ext);
        stem.with_file_name(n)
    };
    match format {
        Format::Glb => name(".glb"),
        Format::Pc2 => name(".pc2"),
        Format::Usda => name(".usda"),
        Format::Obj => stem,
    }
}

/// The files (or, for OBJ frames, the folder) a clip's output occupies.
fn occupies(out: &Path, format: Format) -> Vec<PathBuf> {
    match format {
        Format::Pc2 => vec![out.to_path_buf(), out.with_extension("obj")],
        _ => vec![out.to_path_buf()],
    }
}

/// One clip of a batch and where it goes.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Planned {
    /// The clip, relative to the mocap folder.
    pub clip: PathBuf,
    /// Its output.
    pub output: PathBuf,
}

/// Two or more clips that would write one output, and could not be told
/// apart by their extensions; or an output that is already something else.
#[derive(Debug, thiserror::Error)]
#[error("{}", self.text())]
pub struct CollisionError {
    /// (output, the clips that want it or why it is taken).
    pub collisions: Vec<(PathBuf, Vec<String>)>,
}

impl CollisionError {
    fn text(&self) -> String {
        let list: Vec<String> = self
            .collisions
            .iter()
            .map(|(out, who)| format!("{}: {}", out.display(), who.join(", ")))
            .collect();
        format!(
            "{} output{} of this batch cannot be written, nothing was converted: {}",
            self.collisions.len(),
            if self.collisions.len() == 1 { "" } else { "s" },
            list.join("; ")
        )
    }
}

/// The plan of a batch: every clip of `all` (the whole library, before
/// sharding, so every shard agrees) with its output under `out_dir`.
///
/// Clips whose outputs would collide — `x.bvh` and `x.amc` both making
/// `x.glb`, or an OBJ-frame folder `walk/` of `walk.bvh` that is also the
/// folder of the clips in `walk/` — get their extension in the name
/// (`x-bvh.glb`, `x-amc.glb`, `walk-bvh/`); the second value lists these
/// renames as `clip -> output` lines. Outputs that still collide, outputs
/// that would take the name of the batch's own files (reports, lock,
/// temporaries), and file outputs that exist as folders are refused before
/// any work.
pub fn plan(
    all: &[PathBuf],
    out_dir: &Path,
    format: Format,
) -> Result<(Vec<Planned>, Vec<String>), CollisionError> {
    let mut plan: Vec<Planned> = all
        .iter()
        .map(|c| Planned {
            clip: c.clone(),
            output: output_path(out_dir, c, format),
        })
        .collect();
    let mut renamed = Vec::new();
    let clashing = clashes(&plan, out_dir, format);
    for &i in clashing.keys() {
        let c = &plan[i].clip;
        let ext = c.extension().unwrap_or_default().to_string_lossy();
        let mut stem = c.file_stem().unwrap_or_default().to_os_string();
        stem.push(format!("-{ext}"));
        let out = with_format(out_dir.join(c).with_file_name(stem), format);
        renamed.push(format!("{} -> {}", c.display(), out.display()));
        plan[i].output = out;
    }
    let mut left: BTreeMap<PathBuf, Vec<String>> = BTreeMap::new();
    for (i, why) in clashes(&plan, out_dir, format) {
        left.entry(plan[i].output.clone())
            .or_default()
            .push(format!("{} ({why})", plan[i].clip.display()));
    }
    if format != Format::Obj {
        for p in &plan {
            for o in occupies(&p.output, format)
                .into_iter()
                .filter(|o| o.is_dir())
            {
                left.entry(o).or_default().push(format!(
                    "{} (a folder of that name exists where its file goes; remove it or write elsewhere)",
                    p.clip.display()
                ));
            }
        }
    }
    if !left.is_empty() {
        return Err(CollisionError {
            collisions: left.into_iter().collect(),
        });
    }
    Ok((plan, renamed))
}

/// Clips whose output collides with another's, with a batch file, or
/// contains another's: index → why.
fn clashes(plan: &[Planned], out_dir: &Path, format: Format) -> BTreeMap<usize, String> {
    let mut owner: HashMap<PathBuf, Vec<usize>> = HashMap::new();
    for (i, p) in plan.iter().enumerate() {
        for o in occupies(&p.output, format) {
            owner.entry(o).or_default().push(i);
        }
    }
    let mut bad = BTreeMap::new();
    for (o, who) in &owner {
        if who.len() > 1 {
            let names: Vec<String> = who
                .iter()
                .map(|&i| plan[i].clip.display().to_string())
                .collect();
            for &i in who {
                bad.insert(i, format!("{} all write {}", names.join(", "), o.display()));
            }
        }
        if reserved(o, out_dir) {
            for &i in who {
                bad.insert(
                    i,
                    format!("{} is a name of the batch's own files", o.display()),
                );
            }
        }
    }
    // An output that is a folder holding other outputs (OBJ frames of
    // `walk.bvh` and the clips in `walk/`).
    let mut holds: HashMap<&Path, usize> = HashMap::new();
    for (o, who) in &owner {
        for a in o.ancestors().skip(1) {
            if a == out_dir || !a.starts_with(out_dir) {
                break;
            }
            holds.entry(a).or_insert(who[0]);
        }
    }
    for (i, p) in plan.iter().enumerate() {
        if let Some(&j) = holds.get(p.output.as_path()) {
            bad.insert(
                i,
                format!(
                    "its output folder {} would also hold the output of {}",
                    p.output.display(),
                    plan[j].clip.display()
                ),
            );
        }
    }
    bad
}

/// Names the batch itself writes in its output folder: reports and locks
/// (`batch*.json/html/svg/lock` at the top) and temporaries anywhere.
fn reserved(o: &Path, out_dir: &Path) -> bool {
    let name = o.file_name().unwrap_or_default().to_string_lossy();
    if is_temporary(&name) {
        return true;
    }
    let ext = o.extension().unwrap_or_default().to_string_lossy();
    o.parent() == Some(out_dir)
        && name.starts_with("batch")
        && matches!(ext.as_ref(), "json" | "html" | "svg" | "lock")
}

/// Prefix of every temporary file or folder this crate writes.
pub(crate) const TEMP_PREFIX: &str = ".surfmotion-";

/// True for the name of a temporary this crate writes: an atomic write's
/// `.surfmotion-XXXXXX.part` file, or a batch's `.surfmotion-XXXXXX-partial`
/// folder of OBJ frames.
pub(crate) fn is_temporary(name: &str) -> bool {
    name.strip_prefix(TEMP_PREFIX)
        .and_then(|r| {
            r.strip_suffix(".part")
                .or_else(|| r.strip_suffix("-partial"))
        })
        .is_some_and(|mid| !mid.is_empty() && mid.bytes().all(|b| b.is_ascii_alphanumeric()))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn planned(names: &[String]) -> Vec<Planned> {
        names
            .iter()
            .map(|n| Planned {
                clip: PathBuf::from(n),
                output: PathBuf::from("out").join(n),
            })
            .collect()
    }

    #[test]
    fn shards_cover_the_list_once() {
        let names: Vec<String> = (0..40).map(|i| format!("d{}/c{i}.bvh", i % 3)).collect();
        let all = planned(&names);
        let mut seen = Vec::new();
        for i in 1..=3 {
            let part = Shard::parse(&format!("{i}/3")).unwrap().select(&all);
            // 40 clips in 3 shards: none empty, none with most of them.
            assert!((5..=25).contains(&part.len()), "{}", part.len());
            seen.extend(part.into_iter().map(|p| p.clip));
        }
        seen.sort();
        let mut want: Vec<PathBuf> = all.iter().map(|p| p.clip.clone()).collect();
        want.sort();
        assert_eq!(seen, want);
        assert!(Shard::parse("0/3").is_err());
        assert!(Shard::parse("4/3").is_err());
        assert!(Shard::parse("a/b").is_err());
        assert!(Shard::parse("3").is_err());
    }

    #[cfg(unix)]
    #[test]
    fn links_are_followed_once_and_real_spellings_win() {
        let d = tempfile::tempdir().unwrap();
        let lib = d.path();
        std::fs::create_dir_all(lib.join("sub/deep")).unwrap();
        for f in ["b.bvh", "sub/a.bvh", "sub/deep/c.AMC", "sub/notes.txt"] {
            std::fs::write(lib.join(f), b"x").unwrap();
        }
        let outside = tempfile::tempdir().unwrap();
        std::fs::write(outside.path().join("o.bvh"), b"x").unwrap();
        let link = |to: &Path, at: &str| std::os::unix::fs::symlink(to, lib.join(at)).unwrap();
        link(Path::new(".."), "sub/loop");
        link(Path::new("../.."), "sub/deep/up");
        link(Path::new("sub/a.bvh"), "also_a.bvh");
        link(Path::new("sub"), "a_linked");
        link(outside.path(), "outside");
        link(Path::new("nowhere"), "dangling.bvh");
        let clips = find_clips(lib).unwrap();
        let want: Vec<PathBuf> = ["b.bvh", "outside/o.bvh", "sub/a.bvh", "sub/deep/c.AMC"]
            .map(PathBuf::from)
            .to_vec();
        assert_eq!(clips, want);
    }

    #[test]
    fn colliding_outputs_are_named_apart_or_refused() {
        let out = Path::new("out");
        let clips: Vec<PathBuf> = ["x.bvh", "x.amc", "walk.bvh", "walk/a.bvh", "y.bvh"]
            .map(PathBuf::from)
            .to_vec();
        let (p, renamed) = plan(&clips, out, Format::Obj).unwrap();
        let outs: Vec<&Path> = p.iter().map(|p| p.output.as_path()).collect();
        assert_eq!(
            outs,
            [
                "out/x-bvh",
                "out/x-amc",
                "out/walk-bvh",
                "out/walk/a",
                "out/y"
            ]
            .map(Path::new)
        );
        assert_eq!(renamed.len(), 3);
        let (p, renamed) = plan(&clips, out, Format::Glb).unwrap();
        assert_eq!(p[2].output, Path::new("out/walk.glb"));
        assert_eq!(renamed.len(), 2);
        // Still one output for two clips: refused.
        let clash: Vec<PathBuf> = ["x.bvh", "x.BVH", "x-bvh.bvh"].map(PathBuf::from).to_vec();
        let e = plan(&clash, out, Format::Glb).unwrap_err();
        assert!(e.to_string().contains("x-bvh.glb"), "{e}");
        // The batch's own names are not outputs.
        let own: Vec<PathBuf> = ["batch.json.bvh", ".surfmotion-ab12CD-partial.bvh"]
            .map(PathBuf::from)
            .to_vec();
        let (p, _) = plan(&own, out, Format::Obj).unwrap();
        assert_eq!(p[0].output, Path::new("out/batch.json-bvh"));
        assert!(is_temporary(".surfmotion-ab12CD-partial"));
        assert!(!is_temporary(".surfmotion-ab12CD-partial-bvh"));
        assert_eq!(p[1].output, Path::new("out/.surfmotion-ab12CD-partial-bvh"));
    }

    /// Clips added to a library (before, among and after the old ones in
    /// sorted order) leave every old clip in its shard; the sorted-list
    /// split `k mod n` moved most of them.
    #[test]
    fn adding_clips_does_not_reshuffle_finished_ones() {
        let old: Vec<String> = (0..30).map(|i| format!("lib/{:03}.bvh", 2 * i)).collect();
        let mut grown = old.clone();
        grown.extend((0..30).map(|i| format!("lib/{:03}.bvh", 2 * i + 1)));
        grown.extend(["aaa/first.amc".to_string(), "zzz/last.bvh".to_string()]);
        grown.sort();
        for n in [2, 4, 7] {
            let shard_in = |list: &[String]| -> HashMap<PathBuf, usize> {
                let all = planned(list);
                (1..=n)
                    .flat_map(|i| {
                        Shard { index: i, count: n }
                            .select(&all)
                            .into_iter()
                            .map(move |p| (p.clip, i))
                    })
                    .collect()
            };
            let (before, after) = (shard_in(&old), shard_in(&grown));
            assert_eq!(after.len(), grown.len());
            for (clip, i) in &before {
                assert_eq!(
                    after[clip],
                    *i,
                    "{} moved in a split of {n}",
                    clip.display()
                );
            }
            // What the old split did: clip k of the sorted list in shard k mod n + 1.
            let by_rank = |list: &[String]| -> HashMap<String, usize> {
                let mut l = list.to_vec();
                l.sort();
                l.into_iter()
                    .enumerate()
                    .map(|(k, c)| (c, k % n + 1))
                    .collect()
            };
            let (rb, ra) = (by_rank(&old), by_rank(&grown));
            assert!(old.iter().filter(|c| rb[*c] != ra[*c]).count() > old.len() / 3);
        }
    }

    /// The hash is part of the format of a split (finished shards are found
    /// again by it): pinned to the value Python computes from the
    /// definition (FNV-1a 64, then SplitMix64's finaliser), and blind to
    /// how the path is spelled.
    #[test]
    fn the_clip_hash_is_pinned() {
        assert_eq!(clip_hash(Path::new("02/02_01.amc")), 0x366f_3262_0665_7db5);
        assert_eq!(
            clip_hash(Path::new("02/02_01.amc")),
            clip_hash(Path::new("./02//02_01.amc"))
        );
        assert_ne!(
            clip_hash(Path::new("02/02_01.amc")),
            clip_hash(Path::new("02_01.amc"))
        );
        assert_eq!(shard_of(Path::new("anything.bvh"), 1), 1);
        assert_eq!(Shard::parse("02/4").unwrap().spelled(), "2/4");
    }

    #[test]
    fn outputs_mirror_the_tree() {
        let p = output_path(Path::new("out"), Path::new("02/02_01.amc"), Format::Glb);
        assert_eq!(p, Path::new("out/02/02_01.glb"));
        let p = output_path(Path::new("out"), Path::new("a.bvh"), Format::Obj);
        assert_eq!(p, Path::new("out/a"));
    }
}
