//! The C allocator's arenas for a live session (issue 45, session 40).
//!
//! glibc gives each thread that allocates its own arena (up to eight per
//! core), and an arena keeps the pages it once used. The live session's
//! two-frame overlap deforms its pairs on the pool's threads, and each
//! thread's arena grew on its own the first time it met a large fold
//! repair — at a loop's start in `live::long`'s replay, after the analysis
//! window had filled (`/proc/PID/smaps`, session 40: the thread arenas
//! 0.4 → 3.1 → 5.8 MiB at the third and fourth loops; the main heap
//! 85.0 → 86.8 MiB at the fifth).
//! With one arena every thread reuses the memory any other freed, so the
//! resident memory stops rising once the largest repair was met.

/// Makes every thread of this process allocate from the main arena
/// (`mallopt(M_ARENA_MAX, 1)`; glibc only, elsewhere nothing). Called
/// before the session starts its threads: a thread keeps the arena it
/// first allocated from.
pub fn one_arena() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: `mallopt` only sets an allocator parameter; no pointer is
    // passed, and a failure (0) leaves the default, which is still correct.
    unsafe {
        libc::mallopt(libc::M_ARENA_MAX, 1);
    }
}
