//! Label-free contact detection in one frame of a character: pairs of
//! surface points close in space but far apart along the surface (a hand
//! resting on the hip, forearms lying on the belly, knees pressed
//! together). Such a frame rigs badly: bone heat and part labels flow across
//! the touching surfaces (issue 41: a fist on the hip made the forearm part
//! the buttock; forearms on the belly left a ridge in every skinned frame).
//!
//! The distance along the surface is the graph distance over the mesh's
//! edges, measured once on a reference frame (the capture deforms nearly
//! isometrically) between *patches*: `patches` seeds taken by farthest-point
//! sampling along the surface, each vertex belonging to its nearest seed.
//! A pair of vertices is apart when their patches' seeds are at least
//! [`ContactOptions::apart`] × height apart along the surface. Seeds are
//! ~3 cm apart on a person; the threshold is ~50 cm, so the patch
//! approximation costs nothing in precision.
//!
//! Cost: `patches` Dijkstra runs over the vertex graph once
//! (O(P · V log V)); per frame, one spatial hash of the vertices with cells
//! of the near distance and a look-up of each close pair's patch distance
//! (O(V · k), k the vertices per cell neighbourhood).

use super::parts::neighbours;
use crate::mesh::Mesh;
use glam::DVec3;
use serde::Serialize;
use std::cmp::Reverse;
use std::collections::{BinaryHeap, HashMap};

/// Thresholds of [`ContactFinder`]; every length is a fraction of the
/// reference frame's height (its bounding box's largest side).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactOptions {
    /// Two surface points closer than this in space touch. Default 0.015
    /// (2.5 cm on a 1.7 m person).
    pub touch: f64,
    /// Closer than this they are near (a limb barely clear of the body),
    /// counted apart from the touching ones to prefer clear frames.
    /// Default 0.045 (7.7 cm).
    pub near: f64,
    /// …provided they lie at least this far apart along the surface.
    /// Default 0.3 (51 cm: more than the armpit's or the crotch's folds,
    /// less than hand to hip or forearm to belly).
    pub apart: f64,
    /// Surface patches for the distance along the surface. Default 600.
    pub patches: usize,
    /// A touching region of fewer vertices is ignored (noise). Default 3.
    pub min_vertices: usize,
    /// Seed the surface patches by position ([`first_seed`]: the vertex
    /// nearest the middle of the reference frame's bounding box, ties by
    /// coordinates), so that which pairs count as apart, and the rest
    /// frame chosen on them, follow the body and not the vertex
    /// numbering. Default false: the first seed is vertex 0 (main's;
    /// samba with its odd ids numbered first then has "1 contact, 4
    /// vertices" on its clear frame 0 and rests on frame 27: session 29).
    /// `SURFMOTION_AUTORIG=patches=position` for the automatic rig.
    pub seed_by_position: bool,
}

impl Default for ContactOptions {
    fn default() -> Self {
        ContactOptions {
            touch: 0.015,
            near: 0.045,
            apart: 0.3,
            patches: 600,
            min_vertices: 3,
            seed_by_position: false,
        }
    }
}

/// One contact in a frame: the touching surfaces, each a connected set of
/// vertices (two sides for a hand on a hip; more when a region touches
/// several others).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Contact {
    /// The touching regions, each sorted vertex ids, largest first.
    pub sides: Vec<Vec<u32>>,
    /// The smallest distance between two touching vertices of different
    /// sides, in the mesh's units.
    pub gap: f64,
    /// The centre of the touching vertices on the frame.
    pub centre: [f64; 3],
}

impl Contact {
    /// Every vertex of every side.
    pub fn vertex_count(&self) -> usize {
        self.sides.iter().map(Vec::len).sum()
    }
}

/// What [`ContactFinder::find`] reads off one frame.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct FrameContacts {
    /// The contacts, most vertices first.
    pub contacts: Vec<Contact>,
    /// Vertices in a contact (all sides).
    pub touching: usize,
    /// Vertices with a surface-far vertex within [`ContactOptions::near`]
    /// (the touching ones included); counted by
    /// [`ContactFinder::find_with_near`] only, else 0.
    pub near: usize,
}

/// Contact detection on frames of one connectivity, prepared once on a
/// reference frame (see the module's documentation).
#[derive(Clone, Debug)]
pub struct ContactFinder {
    n: usize,
    nb: Vec<Vec<u32>>,
    /// Patch (seed index) of each vertex.
    patch: Vec<u32>,
    /// Seeds × seeds: true when the two patches are apart along the surface.
    apart: Vec<bool>,
    seeds: usize,
    height: f64,
    opts: ContactOptions,
}

impl ContactFinder {
    /// Prepares the finder on `mesh` (its positions are the reference
    /// frame the surface distances are measured on).
    pub fn new(mesh: &Mesh, opts: ContactOptions) -> ContactFinder {
        let (p, t) = (mesh.positions(), mesh.triangles());
        let n = p.len();
        let nb = neighbours(n, t);
        let b = mesh.bounds();
        let height = (0..3)
            .map(|k| b.max[k] - b.min[k])
            .fold(0.0, f64::max)
            .max(f64::MIN_POSITIVE);
        let limit = opts.apart * height;
        let k = opts.patches.clamp(1, n.max(1));
        // Farthest-point sampling along the surface; each run from a new
        // seed also gives its distance to every earlier seed (symmetric).
        // A vertex in no triangle is no surface: never a seed (its best
        // distance starts at 0) and never in a pair (`apart_pairs`).
        let stray: Vec<bool> = nb.iter().map(Vec::is_empty).collect();
        let mut best: Vec<f64> = stray
            .iter()
            .map(|&s| if s { 0.0 } else { f64::INFINITY })
            .collect();
        let mut patch = vec![0u32; n];
        let mut seeds: Vec<u32> = Vec::with_capacity(k);
        let mut apart = vec![false; k * k];
        let mut dist = vec![f64::INFINITY; n];
        let mut next = if opts.seed_by_position {
            first_seed(p, &stray)
        } else {
            stray.iter().position(|&s| !s).unwrap_or(0) as u32
        };
        // A mesh of several pieces: vertices no seed reaches stay at
        // infinity and become seeds in turn.
        while seeds.len() < k && n > 0 {
            let s = seeds.len();
            seeds.push(next);
            dijkstra(p, &nb, next, &mut dist);
            for (j, &q) in seeds[..s].iter().enumerate() {
                let far = dist[q as usize] >= limit;
                apart[s * k + j] = far;
                apart[j * k + s] = far;
            }
            for v in 0..n {
                if dist[v] < best[v] {
                    best[v] = dist[v];
                    patch[v] = s as u32;
                }
            }
            let (far_v, far_d) = best
                .iter()
                .enumerate()
                .max_by(|a, b| {
                    let o = a.1.total_cmp(b.1);
                    match opts.seed_by_position {
                        true => o.then_with(|| by_place(p[b.0], p[a.0])),
                        false => o,
                    }
                })
                .map(|(v, d)| (v as u32, *d))
                .unwrap_or((0, 0.0));
            if far_d <= 0.0 {
                break;
            }
            next = far_v;
        }
        let used = seeds.len();
        // Compact the matrix to the seeds used.
        let mut compact = vec![false; used * used];
        for i in 0..used {
            for j in 0..used {
                compact[i * used + j] = apart[i * k + j];
            }
        }
        ContactFinder {
            n,
            nb,
            patch,
            apart: compact,
            seeds: used,
            height,
            opts,
        }
    }

    /// The reference frame's height (its bounding box's largest side), in
    /// the mesh's units.
    pub fn height(&self) -> f64 {
        self.height
    }

    /// The options.
    pub fn options(&self) -> &ContactOptions {
        &self.opts
    }

    /// True when vertices `a` and `b` lie apart along the surface.
    pub fn apart(&self, a: u32, b: u32) -> bool {
        let (pa, pb) = (self.patch[a as usize], self.patch[b as usize]);
        self.apart[pa as usize * self.seeds + pb as usize]
    }

    /// The contacts of one frame (`positions`: one per vertex of the
    /// reference mesh; a frame of another vertex count has none).
    /// [`FrameContacts::near`] is left at 0: see [`ContactFinder::near`].
    pub fn find(&self, positions: &[[f64; 3]]) -> FrameContacts {
        if positions.len() != self.n || self.n == 0 {
            return FrameContacts::default();
        }
        let mut pairs: Vec<(u32, u32, f64)> = Vec::new();
        self.apart_pairs(positions, self.opts.touch * self.height, |a, b, d| {
            pairs.push((a, b, d))
        });
        let contacts = self.group(positions, &pairs);
        FrameContacts {
            touching: contacts.iter().map(Contact::vertex_count).sum(),
            contacts,
            near: 0,
        }
    }

    /// [`ContactFinder::find`] with [`FrameContacts::near`] counted (about
    /// 20 times the cost: the near distance's cells hold more vertices).
    pub fn find_with_near(&self, positions: &[[f64; 3]]) -> FrameContacts {
        let mut c = self.find(positions);
        c.near = self.near(positions);
        c
    }

    /// Vertices of a frame with a vertex apart along the surface within
    /// [`ContactOptions::near`] in space.
    pub fn near(&self, positions: &[[f64; 3]]) -> usize {
        if positions.len() != self.n || self.n == 0 {
            return 0;
        }
        let mut is_near = vec![false; self.n];
        let r = self.opts.near.max(self.opts.touch) * self.height;
        self.apart_pairs(positions, r, |a, b, _| {
            is_near[a as usize] = true;
            is_near[b as usize] = true;
        });
        is_near.iter().filter(|&&b| b).count()
    }

    /// Calls `f(a, b, distance)` for every pair `a < b` of vertices closer
    /// than `r` in space and apart along the surface.
    fn apart_pairs(&self, positions: &[[f64; 3]], r: f64, mut f: impl FnMut(u32, u32, f64)) {
        let cell = |x: [f64; 3]| {
            [
                (x[0] / r).floor() as i64,
                (x[1] / r).floor() as i64,
                (x[2] / r).floor() as i64,
            ]
        };
        let mut grid: HashMap<[i64; 3], Vec<u32>> = HashMap::new();
        for (v, x) in positions.iter().enumerate() {
            if !self.nb[v].is_empty() {
                grid.entry(cell(*x)).or_default().push(v as u32);
            }
        }
        let r2 = r * r;
        for (c, list) in &grid {
            for dx in -1..=1 {
                for dy in -1..=1 {
                    for dz in -1..=1 {
                        let Some(other) = grid.get(&[c[0] + dx, c[1] + dy, c[2] + dz]) else {
                            continue;
                        };
                        for &v in list {
                            let pv = self.patch[v as usize] as usize * self.seeds;
                            let xv = positions[v as usize];
                            for &u in other {
                                if u <= v || !self.apart[pv + self.patch[u as usize] as usize] {
                                    continue;
                                }
                                let xu = positions[u as usize];
                                let d2 = (xv[0] - xu[0]).powi(2)
                                    + (xv[1] - xu[1]).powi(2)
                                    + (xv[2] - xu[2]).powi(2);
                                if d2 < r2 {
                                    f(v, u, d2.sqrt());
                                }
                            }
                        }
                    }
                }
            }
        }
    }

    /// The touching pairs grouped into contacts: touching vertices joined
    /// along the mesh into regions, regions joined by their pairs.
    fn group(&self, positions: &[[f64; 3]], pairs: &[(u32, u32, f64)]) -> Vec<Contact> {
        let mut touching = vec![false; self.n];
        for &(a, b, _) in pairs {
            touching[a as usize] = true;
            touching[b as usize] = true;
        }
        // Regions: connected components of touching vertices.
        let mut region = vec![u32::MAX; self.n];
        let mut regions: Vec<Vec<u32>> = Vec::new();
        for s in 0..self.n {
            if !touching[s] || region[s] != u32::MAX {
                continue;
            }
            let r = regions.len() as u32;
            region[s] = r;
            let mut stack = vec![s as u32];
            let mut members = Vec::new();
            while let Some(v) = stack.pop() {
                members.push(v);
                for &u in &self.nb[v as usize] {
                    if touching[u as usize] && region[u as usize] == u32::MAX {
                        region[u as usize] = r;
                        stack.push(u);
                    }
                }
            }
            members.sort_unstable();
            regions.push(members);
        }
        // Contacts: regions joined by a touching pair (union-find).
        let mut parent: Vec<usize> = (0..regions.len()).collect();
        fn root(parent: &mut [usize], mut i: usize) -> usize {
            while parent[i] != i {
                parent[i] = parent[parent[i]];
                i = parent[i];
            }
            i
        }
        let mut gap: HashMap<usize, f64> = HashMap::new();
        for &(a, b, _) in pairs {
            let (ra, rb) = (region[a as usize] as usize, region[b as usize] as usize);
            let (x, y) = (root(&mut parent, ra), root(&mut parent, rb));
            if x != y {
                parent[y] = x;
            }
        }
        for &(a, _, d) in pairs {
            let r = root(&mut parent, region[a as usize] as usize);
            let g = gap.entry(r).or_insert(f64::INFINITY);
            *g = g.min(d);
        }
        let mut by_root: HashMap<usize, Vec<usize>> = HashMap::new();
        for r in 0..regions.len() {
            by_root.entry(root(&mut parent, r)).or_default().push(r);
        }
        let mut out: Vec<Contact> = by_root
            .into_iter()
            .filter_map(|(r, members)| {
                let mut sides: Vec<Vec<u32>> =
                    members.iter().map(|&m| regions[m].clone()).collect();
                sides.sort_by(|a, b| b.len().cmp(&a.len()).then(a.cmp(b)));
                let count: usize = sides.iter().map(Vec::len).sum();
                if count < self.opts.min_vertices {
                    return None;
                }
                let centre = sides
                    .iter()
                    .flatten()
                    .map(|&v| DVec3::from_array(positions[v as usize]))
                    .sum::<DVec3>()
                    / count as f64;
                Some(Contact {
                    sides,
                    gap: gap.get(&r).copied().unwrap_or(0.0),
                    centre: centre.to_array(),
                })
            })
            .collect();
        out.sort_by(|a, b| {
            b.vertex_count()
                .cmp(&a.vertex_count())
                .then(a.sides.cmp(&b.sides))
        });
        out
    }
}

/// The patches' first seed with [`ContactOptions::seed_by_position`]:
/// the vertex nearest the middle of `p`'s bounding box (ties: the lesser
/// coordinates), not a vertex in no triangle (`stray`). 0 for an empty
/// mesh.
fn first_seed(p: &[[f64; 3]], stray: &[bool]) -> u32 {
    let Some(first) = p.first() else { return 0 };
    let (lo, hi) = p.iter().fold((*first, *first), |(mut lo, mut hi), q| {
        for k in 0..3 {
            lo[k] = lo[k].min(q[k]);
            hi[k] = hi[k].max(q[k]);
        }
        (lo, hi)
    });
    let mid = DVec3::from_array(lo).lerp(DVec3::from_array(hi), 0.5);
    let d = |v: usize| DVec3::from_array(p[v]).distance_squared(mid);
    (0..p.len())
        .filter(|&v| !stray[v])
        .min_by(|&a, &b| d(a).total_cmp(&d(b)).then_with(|| by_place(p[a], p[b])))
        .unwrap_or(0) as u32
}

/// Two points ordered by their coordinates (x, then y, then z).
fn by_place(a: [f64; 3], b: [f64; 3]) -> std::cmp::Ordering {
    a.iter()
        .zip(&b)
        .map(|(x, y)| x.total_cmp(y))
        .find(|o| o.is_ne())
        .unwrap_or(std::cmp::Ordering::Equal)
}

/// Graph distances (edge lengths on `p`) from `source` into `dist`.
fn dijkstra(p: &[[f64; 3]], nb: &[Vec<u32>], source: u32, dist: &mut [f64]) {
    dist.fill(f64::INFINITY);
    dist[source as usize] = 0.0;
    let mut heap = BinaryHeap::new();
    heap.push(Reverse((Key(0.0), source)));
    while let Some(Reverse((Key(d), v))) = heap.pop() {
        if d > dist[v as usize] {
            continue;
        }
        let pv = DVec3::from_array(p[v as usize]);
        for &u in &nb[v as usize] {
            let nd = d + pv.distance(DVec3::from_array(p[u as usize]));
            if nd < dist[u as usize] {
                dist[u as usize] = nd;
                heap.push(Reverse((Key(nd), u)));
            }
        }
    }
}

/// A finite distance ordered for the heap.
#[derive(Clone, Copy, PartialEq)]
struct Key(f64);
impl Eq for Key {}
impl PartialOrd for Key {
    fn partial_cmp(&self, o: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(o))
    }
}
impl Ord for Key {
    fn cmp(&self, o: &Self) -> std::cmp::Ordering {
        self.0.total_cmp(&o.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A strip folded into a U: its two arms face each other across a gap.
    fn folded(gap: f64) -> Mesh {
        // A ladder of 2 × 41 vertices along a path 4 long: 0..1.8 along x
        // at z = 0, a half circle of radius gap/2, back along x at z = gap.
        let mut p = Vec::new();
        let r = gap / 2.0;
        let path: Vec<[f64; 2]> = (0..=40)
            .map(|i| {
                let s = i as f64 / 40.0;
                let straight = 1.8;
                let arc = std::f64::consts::PI * r;
                let len = 2.0 * straight + arc;
                let t = s * len;
                if t <= straight {
                    [straight - t, 0.0]
                } else if t <= straight + arc {
                    let a = (t - straight) / r;
                    [-r * a.sin(), r - r * a.cos()]
                } else {
                    [t - straight - arc, gap]
                }
            })
            .collect();
        for q in &path {
            p.push([q[0], 0.0, q[1]]);
            p.push([q[0], 0.1, q[1]]);
        }
        let mut t = Vec::new();
        for i in 0..40u32 {
            let (a, b, c, d) = (2 * i, 2 * i + 1, 2 * i + 2, 2 * i + 3);
            t.push([a, c, b]);
            t.push([b, c, d]);
        }
        Mesh::new(p, t).unwrap()
    }

    #[test]
    fn folded_strip_touches_across_the_fold_not_along_it() {
        let m = folded(0.02);
        let f = ContactFinder::new(&m, ContactOptions::default());
        let c = f.find(m.positions());
        assert!(!c.contacts.is_empty(), "the arms 2 cm apart touch");
        let top = &c.contacts[0];
        assert_eq!(top.sides.len(), 2, "{top:?}");
        assert!(top.gap <= 0.02 + 1e-9, "{}", top.gap);
        // No touching vertex is near the fold (surface-near there).
        for v in top.sides.iter().flatten() {
            let x = m.positions()[*v as usize][0];
            assert!(x > 0.2, "vertex {v} at x = {x}");
        }
        // Opened out: the same strip flat has no contact.
        let flat: Vec<[f64; 3]> = m
            .positions()
            .iter()
            .enumerate()
            .map(|(v, _)| {
                let i = (v / 2) as f64;
                [i * 0.1, (v % 2) as f64 * 0.1, 0.0]
            })
            .collect();
        let c = f.find_with_near(&flat);
        assert!(c.contacts.is_empty() && c.near == 0, "{c:?}");
    }

    #[test]
    fn the_patches_follow_the_surface_not_the_vertex_numbering() {
        let m = folded(0.02);
        let n = m.vertex_count();
        // Few patches (on a person they are ~3 cm across): where they
        // are seeded decides which pairs are apart.
        let o = ContactOptions {
            patches: 6,
            seed_by_position: true,
            ..ContactOptions::default()
        };
        let f = ContactFinder::new(&m, o);
        for order in [
            (0..n as u32).rev().collect::<Vec<u32>>(),
            (0..n as u32).map(|v| (v * 37 + 11) % n as u32).collect(),
        ] {
            // New vertex k is old vertex order[k].
            let mut new_of = vec![0u32; n];
            for (k, &o) in order.iter().enumerate() {
                new_of[o as usize] = k as u32;
            }
            let p: Vec<[f64; 3]> = order.iter().map(|&o| m.positions()[o as usize]).collect();
            let t = m
                .triangles()
                .iter()
                .map(|t| t.map(|i| new_of[i as usize]))
                .collect();
            let g = ContactFinder::new(&Mesh::new(p.clone(), t).unwrap(), o);
            for a in 0..n as u32 {
                for b in 0..n as u32 {
                    assert_eq!(
                        f.apart(a, b),
                        g.apart(new_of[a as usize], new_of[b as usize]),
                        "{a} {b}"
                    );
                }
            }
            let (c, d) = (f.find_with_near(m.positions()), g.find_with_near(&p));
            assert_eq!((c.touching, c.near), (d.touching, d.near));
        }
    }

    /// A point in no triangle 1 cm off a wide fold (no contact of its
    /// own) is no surface: numbered first or last, by either seeding, the
    /// fold stays as it is without the point.
    #[test]
    fn a_vertex_in_no_triangle_touches_nothing() {
        let m = folded(0.06);
        for seed_by_position in [false, true] {
            let o = ContactOptions {
                seed_by_position,
                ..ContactOptions::default()
            };
            let clean = ContactFinder::new(&m, o).find_with_near(m.positions());
            for first in [false, true] {
                let (mut p, mut t) = (m.positions().to_vec(), m.triangles().to_vec());
                // Beside vertex 10 (an arm), 1 cm towards the other arm.
                let q = [p[10][0], p[10][1], p[10][2] + 0.01];
                if first {
                    p.insert(0, q);
                    t.iter_mut().for_each(|t| *t = t.map(|v| v + 1));
                } else {
                    p.push(q);
                }
                let mesh = Mesh::new(p, t).unwrap();
                let c = ContactFinder::new(&mesh, o).find_with_near(mesh.positions());
                assert!(c.contacts.is_empty(), "{first}: {:?}", c.contacts);
                assert_eq!(
                    (c.touching, c.near),
                    (clean.touching, clean.near),
                    "{first}"
                );
            }
        }
    }

    #[test]
    fn a_wide_fold_is_near_but_not_touching() {
        let m = folded(0.06);
        let f = ContactFinder::new(&m, ContactOptions::default());
        let c = f.find_with_near(m.positions());
        assert!(c.contacts.is_empty(), "{:?}", c.contacts);
        assert!(c.near > 0);
    }
}
