//! faer's symbolic analysis, counted apart in the library's tests.
//!
//! In the library's tests, every allocation call (`alloc`, `alloc_zeroed`,
//! `realloc`) is counted on the thread that makes it, apart from those
//! made inside faer's symbolic analysis ([`faer_symbolic`]): the
//! tests of the repair's memory (`deform::unflip`) read the counts
//! ([`calls`]). Per thread, so tests running at once do not mix.

/// Outside the tests, faer's symbolic analysis as it is: `f()`.
#[cfg(not(test))]
pub(super) fn faer_symbolic<T>(f: impl FnOnce() -> T) -> T {
    f()
}

#[cfg(test)]
pub(crate) use counting::{calls, faer_symbolic};

/// The counting allocator of the library's tests.
#[cfg(test)]
mod counting {
    use std::alloc::{GlobalAlloc, Layout, System};
    use std::cell::Cell;

    thread_local! {
        /// Calls outside and inside faer's symbolic analysis.
        static CALLS: Cell<[usize; 2]> = const { Cell::new([0, 0]) };
        static IN_SYMBOLIC: Cell<bool> = const { Cell::new(false) };
    }

    /// The system allocator, counted.
    struct Counting;

    #[global_allocator]
    static COUNTING: Counting = Counting;

    fn bump() {
        let inside = IN_SYMBOLIC.try_with(Cell::get).unwrap_or(false);
        let _ = CALLS.try_with(|c| {
            let mut v = c.get();
            v[usize::from(inside)] += 1;
            c.set(v);
        });
    }

    // SAFETY: every call is passed on to `System` unchanged; the counting
    // touches only const-initialised thread-locals (no allocation).
    unsafe impl GlobalAlloc for Counting {
        unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
            bump();
            // SAFETY: the caller's contract, passed on.
            unsafe { System.alloc(layout) }
        }
        unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
            bump();
            // SAFETY: as above.
            unsafe { System.alloc_zeroed(layout) }
        }
        unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
            // SAFETY: as above.
            unsafe { System.dealloc(ptr, layout) }
        }
        unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
            bump();
            // SAFETY: as above.
            unsafe { System.realloc(ptr, layout, new_size) }
        }
    }

    /// This thread's allocation calls so far: `[outside, inside]` faer's
    /// symbolic analysis.
    pub(crate) fn calls() -> [usize; 2] {
        CALLS.with(Cell::get)
    }

    /// `f()`, its allocation calls counted as faer's symbolic analysis'.
    pub(crate) fn faer_symbolic<T>(f: impl FnOnce() -> T) -> T {
        IN_SYMBOLIC.with(|s| s.set(true));
        let r = f();
        IN_SYMBOLIC.with(|s| s.set(false));
        r
    }
}
