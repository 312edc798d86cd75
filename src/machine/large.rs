//! The allocator's large blocks ([`KEPT_FROM_BYTES`] or more): each a
//! mapping of its own, kept when freed (up to [`KEPT_MAX_BYTES`] and
//! [`SLOTS`] blocks in all, the oldest unmapped first) and handed out again
//! resized in place by `mremap`, so that its pages are neither handed back
//! to the kernel nor zeroed and faulted in anew.
//!
//! Why: a mechanical step of the large arch allocates and frees blocks of
//! hundreds of MB to GBs (a refactorisation's matrix, the correction's
//! columns, each new live set's factor). glibc maps every such block afresh
//! and unmaps it when freed, and on the virtual machines this runs on the
//! kernel reports freed memory to the host within seconds (virtio-balloon
//! free page reporting), so the next block's pages come from the host:
//! measured with a C probe, 2 GB first touched in 3.8–4.5 s (0.5 GB/s) by
//! a new process, 0.23 s (9 GB/s) when the same process had just freed as
//! much. A block kept is reused however long it waited.
//!
//! A kept block is the smallest that holds the request, shrunk to it (its
//! tail returned to the kernel), else the largest, grown by `mremap` (the
//! kernel moves its page tables, not its bytes; the grown tail is fresh).
//! A zeroed request zeroes the reused bytes itself. Sizes are rounded to
//! whole huge pages, so a block's mapping length follows from its layout.
//!
//! Verified by the tests below (reuse, zeroing, contents kept by
//! `realloc`, the bound on kept bytes) and by the integration tests, whose
//! global allocator this is.

use super::{Layout, HUGE_PAGE_BYTES};

/// Blocks of this size or more are mapped here \[bytes\]: glibc's own
/// mapping threshold ([`super::MAPPED_FROM_BYTES`]), below which its heap
/// keeps what is freed.
pub const KEPT_FROM_BYTES: usize = super::MAPPED_FROM_BYTES;
/// Freed bytes kept for reuse, at most: about one large factor of the
/// large arch (1.1–2.0 GB), so the peak resident memory grows by at most
/// that (measured: 0.2–0.3 GB more on the large complete dam's step,
/// 0.1–0.2 GB less on the large arch's late days, whose blocks are
/// reused rather than freed and mapped again).
pub const KEPT_MAX_BYTES: usize = 2 << 30;
/// Freed blocks kept, at most.
pub const SLOTS: usize = 8;

/// Whether a block of `layout` is one of the large ones.
pub fn takes(layout: Layout) -> bool {
    cfg!(target_os = "linux") && layout.size() >= KEPT_FROM_BYTES && layout.align() <= 4096
}

#[cfg(target_os = "linux")]
pub use linux::{alloc, dealloc, realloc};

#[cfg(target_os = "linux")]
mod linux {
    use super::{HUGE_PAGE_BYTES, KEPT_MAX_BYTES, SLOTS};
    use std::sync::Mutex;

    /// The kept blocks: (address, mapped length), oldest first.
    struct Kept {
        blocks: [(usize, usize); SLOTS],
        len: usize,
    }

    impl Kept {
        fn remove(&mut self, i: usize) -> (usize, usize) {
            let block = self.blocks[i];
            self.blocks.copy_within(i + 1..self.len, i);
            self.len -= 1;
            block
        }

        fn bytes(&self) -> usize {
            self.blocks[..self.len].iter().map(|b| b.1).sum()
        }
    }

    // A std Mutex allocates nothing (a futex on Linux), so the allocator
    // may hold it.
    static KEPT: Mutex<Kept> = Mutex::new(Kept {
        blocks: [(0, 0); SLOTS],
        len: 0,
    });

    fn kept() -> std::sync::MutexGuard<'static, Kept> {
        KEPT.lock().unwrap_or_else(|e| e.into_inner())
    }

    fn mapped_len(size: usize) -> usize {
        size.next_multiple_of(HUGE_PAGE_BYTES)
    }

    /// Bytes kept for reuse now.
    #[cfg(test)]
    pub fn kept_bytes() -> usize {
        kept().bytes()
    }

    /// Unmaps every kept block (tests start from none).
    #[cfg(test)]
    pub fn unmap_kept() {
        let mut kept = kept();
        while kept.len > 0 {
            let (p, len) = kept.remove(0);
            // SAFETY: a kept mapping no one holds.
            unsafe { libc::munmap(p as *mut libc::c_void, len) };
        }
    }

    /// The kept block to reuse for `len` bytes: the smallest that holds
    /// them, else the largest.
    fn take(len: usize) -> Option<(usize, usize)> {
        let mut kept = kept();
        let n = kept.len;
        let fits = (0..n)
            .filter(|&i| kept.blocks[i].1 >= len)
            .min_by_key(|&i| kept.blocks[i].1);
        let i = fits.or_else(|| (0..n).max_by_key(|&i| kept.blocks[i].1))?;
        Some(kept.remove(i))
    }

    /// A block of `size` bytes (zeroed if asked), null if the kernel has
    /// no memory for it.
    pub fn alloc(size: usize, zeroed: bool) -> *mut u8 {
        let len = mapped_len(size);
        let Some((p, old)) = take(len) else {
            return fresh(len);
        };
        let p = p as *mut libc::c_void;
        if old >= len {
            // SAFETY (both calls): the mapping `p` of `old` bytes is ours;
            // shrunk in place, its tail goes back to the kernel, and should
            // the kernel refuse, the tail is unmapped instead.
            if old > len && unsafe { libc::mremap(p, old, len, 0) } == libc::MAP_FAILED {
                unsafe { libc::munmap((p as *mut u8).add(len) as *mut libc::c_void, old - len) };
            }
            if zeroed {
                // SAFETY: the mapping is ours and at least `size` long.
                unsafe { std::ptr::write_bytes(p as *mut u8, 0, size) };
            }
            return p as *mut u8;
        }
        // SAFETY: growing a mapping of ours.
        let Some(q) = (unsafe { remap(p as *mut u8, old, len) }) else {
            // SAFETY: on failure the old mapping is untouched and ours.
            unsafe { libc::munmap(p, old) };
            return fresh(len);
        };
        if zeroed {
            // SAFETY: the first `old` bytes are the reused ones; the grown
            // tail is fresh, zeroed by the kernel.
            unsafe { std::ptr::write_bytes(q, 0, old) };
        }
        q
    }

    /// The mapping `p` of `old_len` bytes resized to `new_len`, its
    /// contents kept (the kernel may move it), advised huge pages; `None`
    /// (and `p` untouched) if the kernel cannot.
    ///
    /// # Safety
    /// `p` is a mapping of ours of `old_len` bytes.
    unsafe fn remap(p: *mut u8, old_len: usize, new_len: usize) -> Option<*mut u8> {
        // SAFETY: the caller's.
        let q = unsafe {
            libc::mremap(
                p as *mut libc::c_void,
                old_len,
                new_len,
                libc::MREMAP_MAYMOVE,
            )
        };
        if q == libc::MAP_FAILED {
            return None;
        }
        super::super::advise_huge_pages(q as *mut u8, new_len);
        Some(q as *mut u8)
    }

    fn fresh(len: usize) -> *mut u8 {
        // SAFETY: a new private anonymous mapping, no address asked for.
        let p = unsafe {
            libc::mmap(
                std::ptr::null_mut(),
                len,
                libc::PROT_READ | libc::PROT_WRITE,
                libc::MAP_PRIVATE | libc::MAP_ANONYMOUS,
                -1,
                0,
            )
        };
        if p == libc::MAP_FAILED {
            return std::ptr::null_mut();
        }
        super::super::advise_huge_pages(p as *mut u8, len);
        p as *mut u8
    }

    /// Keeps the freed block `p` of `size` bytes, unmapping the oldest
    /// kept ones past the bounds (outside the lock).
    ///
    /// # Safety
    /// `p` is a block of `size` bytes from [`alloc`] or [`realloc`], not
    /// used after this call.
    pub unsafe fn dealloc(p: *mut u8, size: usize) {
        let len = mapped_len(size);
        let mut unmap = [(0usize, 0usize); SLOTS + 1];
        let mut n_unmap = 0;
        if len > KEPT_MAX_BYTES {
            unmap[0] = (p as usize, len);
            n_unmap = 1;
        } else {
            let mut kept = kept();
            while kept.len == SLOTS || kept.bytes() + len > KEPT_MAX_BYTES {
                unmap[n_unmap] = kept.remove(0);
                n_unmap += 1;
            }
            let n = kept.len;
            kept.blocks[n] = (p as usize, len);
            kept.len += 1;
        }
        for &(q, l) in &unmap[..n_unmap] {
            // SAFETY: a mapping of ours that no one holds any more.
            unsafe { libc::munmap(q as *mut libc::c_void, l) };
        }
    }

    /// The block `p` of `old` bytes resized to `new` bytes, its contents
    /// kept; null (and `p` untouched) if the kernel cannot.
    ///
    /// # Safety
    /// `p` is a block of `old` bytes from [`alloc`] or [`realloc`]; `new`
    /// is at least [`super::KEPT_FROM_BYTES`].
    pub unsafe fn realloc(p: *mut u8, old: usize, new: usize) -> *mut u8 {
        let (old_len, new_len) = (mapped_len(old), mapped_len(new));
        if old_len == new_len {
            return p;
        }
        // SAFETY: `p` is a mapping of ours of `old_len` bytes.
        unsafe { remap(p, old_len, new_len) }.unwrap_or(std::ptr::null_mut())
    }
}

/// Elsewhere no block is large ([`takes`] is false): these are never called.
#[cfg(not(target_os = "linux"))]
mod elsewhere {
    pub fn alloc(_: usize, _: bool) -> *mut u8 {
        std::ptr::null_mut()
    }
    pub unsafe fn dealloc(_: *mut u8, _: usize) {}
    pub unsafe fn realloc(_: *mut u8, _: usize, _: usize) -> *mut u8 {
        std::ptr::null_mut()
    }
}
#[cfg(not(target_os = "linux"))]
pub use elsewhere::{alloc, dealloc, realloc};

#[cfg(all(test, target_os = "linux"))]
mod tests {
    use super::linux::{kept_bytes, unmap_kept};
    use super::*;
    use std::sync::Mutex;

    /// The tests share the one set of kept blocks: one at a time.
    static SERIAL: Mutex<()> = Mutex::new(());

    const MB: usize = 1 << 20;

    fn filled(size: usize, byte: u8) -> *mut u8 {
        let p = alloc(size, false);
        assert!(!p.is_null());
        // SAFETY: a fresh block of `size` bytes.
        unsafe { std::ptr::write_bytes(p, byte, size) };
        p
    }

    fn all(p: *const u8, size: usize, byte: u8) -> bool {
        // SAFETY: `p` is a live block of at least `size` bytes.
        unsafe { std::slice::from_raw_parts(p, size) }
            .iter()
            .all(|&b| b == byte)
    }

    /// A freed block is handed out again (the smallest that fits, shrunk
    /// to the request), zeroed when asked; a request larger than every
    /// kept block grows the largest, its reused bytes zeroed and its tail
    /// fresh.
    #[test]
    fn freed_blocks_are_handed_out_again_and_zeroed_when_asked() {
        let _one = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
        unmap_kept();
        let (small, big) = (filled(40 * MB, 7), filled(96 * MB, 9));
        // SAFETY: both blocks are ours, freed once.
        unsafe { dealloc(big, 96 * MB) };
        unsafe { dealloc(small, 40 * MB) };
        let p = alloc(36 * MB, true);
        assert_eq!(p, small, "the smallest kept block that fits");
        assert!(all(p, 36 * MB, 0));
        let q = alloc(200 * MB, true);
        assert!(!q.is_null());
        assert!(all(q, 200 * MB, 0), "reused bytes zeroed, tail fresh");
        let r = alloc(64 * MB, false);
        assert!(!r.is_null());
        // SAFETY: each block is ours, freed once with its size.
        unsafe {
            dealloc(p, 36 * MB);
            dealloc(q, 200 * MB);
            dealloc(r, 64 * MB);
        }
        assert!(kept_bytes() <= KEPT_MAX_BYTES);
    }

    /// `realloc` keeps the contents, growing and shrinking.
    #[test]
    fn realloc_keeps_the_contents() {
        let _one = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
        unmap_kept();
        let p = filled(40 * MB, 5);
        // SAFETY: `p` is ours with 40 MB; each result replaces it.
        let q = unsafe { realloc(p, 40 * MB, 300 * MB) };
        assert!(!q.is_null());
        assert!(all(q, 40 * MB, 5));
        let r = unsafe { realloc(q, 300 * MB, 33 * MB) };
        assert!(all(r, 33 * MB, 5));
        unsafe { dealloc(r, 33 * MB) };
    }

    /// Freed blocks past the bounds are unmapped, the oldest first: the
    /// kept bytes never pass [`KEPT_MAX_BYTES`], nor the blocks [`SLOTS`].
    #[test]
    fn kept_bytes_are_bounded() {
        let _one = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
        unmap_kept();
        // untouched mappings: address space only
        let blocks: Vec<*mut u8> = (0..3).map(|_| alloc(900 * MB, false)).collect();
        let small: Vec<*mut u8> = (0..SLOTS + 2).map(|_| alloc(32 * MB, false)).collect();
        for &p in &blocks {
            // SAFETY: ours, freed once.
            unsafe { dealloc(p, 900 * MB) };
            assert!(kept_bytes() <= KEPT_MAX_BYTES);
        }
        for &p in &small {
            // SAFETY: ours, freed once.
            unsafe { dealloc(p, 32 * MB) };
            assert!(kept_bytes() <= KEPT_MAX_BYTES);
        }
        assert_eq!(kept_bytes(), SLOTS * 32 * MB, "the oldest unmapped first");
    }
}
