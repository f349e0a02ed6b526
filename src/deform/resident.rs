//! Reused buffers made resident when they grow, not when a later frame
//! first reaches into them.
//!
//! A buffer that only grows (the fold repair's, [`super::unflip`]) is
//! reserved once, but the system maps its pages only when they are first
//! written: a large allocation comes from `mmap` untouched, and a grown
//! `Vec`'s spare capacity is untouched until a larger patch fills it. So
//! the resident memory of a long session kept rising after the heap had
//! stopped growing — the live session's second overlap slot, reserved to
//! the first slot's capacity, paged its 8.9 MiB in over the following
//! pairs (issue 45, `live::long`). [`page_in`] writes one element of every
//! page of a buffer's capacity, so a buffer is resident from the moment it
//! is reserved; [`Resident`] does it only when the capacities changed.

use std::mem::MaybeUninit;

/// The smallest page size the buffers are walked by (bytes): every page
/// of a larger page size is written too.
const PAGE: usize = 4096;

/// `v`'s capacity in bytes; with `touch`, first writes one element of
/// every page of it: the elements in use keep their values, the spare
/// capacity is zeroed where written (it holds no values).
pub(crate) fn page_in<T: Copy>(v: &mut Vec<T>, touch: bool) -> usize {
    let size = std::mem::size_of::<T>().max(1);
    if touch {
        let step = (PAGE / size).max(1);
        let n = v.len();
        for i in (0..n).step_by(step).chain(n.checked_sub(1)) {
            // An opaque copy of the value: the store is not elided.
            v[i] = std::hint::black_box(v[i]);
        }
        let spare = v.spare_capacity_mut();
        let last = spare.len().checked_sub(1);
        for i in (0..spare.len()).step_by(step).chain(last) {
            spare[i] = MaybeUninit::zeroed();
        }
    }
    v.capacity() * size
}

/// [`page_in`] for raw scratch bytes (faer's stack buffers).
pub(crate) fn page_in_bytes(b: &mut [MaybeUninit<u8>], touch: bool) -> usize {
    if touch {
        let last = b.len().checked_sub(1);
        for i in (0..b.len()).step_by(PAGE).chain(last) {
            b[i] = MaybeUninit::new(0);
        }
    }
    b.len()
}

/// Buffers that can say their capacity in bytes and page it in
/// ([`page_in`] over each).
pub(crate) trait Resident {
    /// The capacity in bytes of every buffer; with `touch`, each paged in.
    fn resident(&mut self, touch: bool) -> usize;
}

/// The capacity made resident last ([`page_in_grown`]).
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct Paged(usize);

/// Pages in `r`'s buffers when their capacity changed since the last call
/// that `paged` remembers (O(buffers) otherwise).
pub(crate) fn page_in_grown(r: &mut impl Resident, paged: &mut Paged) {
    let now = r.resident(false);
    if now != paged.0 {
        paged.0 = r.resident(true);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Pages of `len` bytes from `p` the system holds resident
    /// (`mincore`; `None` off Linux or when it fails).
    fn resident_pages(p: *const u8, len: usize) -> Option<usize> {
        if !cfg!(target_os = "linux") {
            return None;
        }
        let page = 4096;
        let start = (p as usize) & !(page - 1);
        let end = (p as usize + len).div_ceil(page) * page;
        let mut flags = vec![0u8; (end - start) / page];
        // SAFETY: the range covers pages of one live allocation, and
        // `flags` holds one byte per page.
        let r =
            unsafe { libc::mincore(start as *mut libc::c_void, end - start, flags.as_mut_ptr()) };
        (r == 0).then(|| flags.iter().filter(|&&f| f & 1 == 1).count())
    }

    #[test]
    fn paging_in_keeps_the_values_and_reports_the_capacity() {
        let mut v: Vec<[f64; 3]> = (0..3000).map(|i| [i as f64, 1.0, 2.0]).collect();
        v.reserve_exact(5000);
        let cap = v.capacity();
        assert_eq!(page_in(&mut v, false), cap * 24);
        assert_eq!(page_in(&mut v, true), cap * 24);
        assert_eq!(v.len(), 3000);
        assert!(
            v.iter()
                .enumerate()
                .all(|(i, x)| *x == [i as f64, 1.0, 2.0])
        );
        let mut b = vec![MaybeUninit::new(7u8); 10_000];
        assert_eq!(page_in_bytes(&mut b, true), 10_000);
    }

    /// A reserved buffer of 64 MiB (its own `mmap`: above glibc's largest
    /// threshold) is not resident until written; paged in, every page of
    /// it is (`mincore` on its pages: other threads' memory aside).
    #[test]
    fn a_reserved_buffer_is_resident_once_paged_in() {
        let mut v: Vec<u64> = Vec::with_capacity(8 << 20);
        let bytes = v.capacity() * 8;
        let Some(reserved) = resident_pages(v.as_ptr().cast(), bytes) else {
            return;
        };
        let pages = bytes / 4096;
        assert!(
            reserved < pages / 2,
            "reserved: {reserved} of {pages} pages"
        );
        let mut paged = Paged::default();
        struct One<'a>(&'a mut Vec<u64>);
        impl Resident for One<'_> {
            fn resident(&mut self, touch: bool) -> usize {
                page_in(self.0, touch)
            }
        }
        page_in_grown(&mut One(&mut v), &mut paged);
        let now = resident_pages(v.as_ptr().cast(), bytes);
        assert!(now >= Some(pages), "paged in: {now:?} of {pages} pages");
        assert!(v.is_empty());
    }
}
