//! What the machine has: its memory, and the memory this process has used.
//! Linux reads `/proc`; elsewhere the answers are `None` and the checks
//! that use them are skipped. And how the process asks glibc's allocator
//! to keep the memory it frees ([`keep_freed_memory`]) and the kernel to
//! back its largest blocks with huge pages ([`LargeBlocksOnHugePages`]).

use std::alloc::{GlobalAlloc, Layout, System};

/// Tells glibc's allocator to keep the memory the process frees instead of
/// handing it back to the kernel at once; call it first thing in `main`,
/// before any thread starts. No answer changes (the demo's run folder is
/// the same to the byte), only where the bytes come from.
///
/// Why: a mechanical step allocates and frees vectors of its live set's
/// size (200 KB on the demo, MBs on the large arch) many times per
/// contact pass, and the factor made ahead on the second core allocates its
/// own buffers. By default glibc serves each block above 128 KB (a
/// threshold that only grows as such blocks are freed) by a fresh `mmap`,
/// whose pages the kernel zeroes on first touch and whose `munmap`
/// interrupts the other core, and it trims the heap's free top back to the
/// kernel beyond 128 KB. Blocks up to 32 MB now come from the heap, the
/// heap grows 256 MB at a time and its free top is never trimmed; larger
/// blocks (factors of the large arch, GBs) are still mapped and unmapped.
/// Measured alone on the 2 cores (27 Nov 2026): the demo's whole
/// construction 69.3–71.1 s against 79.5–82.1 s, peak 606–624 MiB against
/// 542 MiB; the Xiaowan-like first 40 days 47.5 s against 47.5 s, peak
/// 2.71 against 2.60 GiB, its complete-dam step 240.8 against 243.9 s at
/// 5.03 against 4.94 GB. (mimalloc as the global allocator gave the demo
/// 68–71 s but the large arch 1 GB more peak; without its delayed purge,
/// no gain.)
///
/// One arena for every thread: glibc gives each new thread an arena of its
/// own, whose heaps are 64 MB mappings, so the threads that analyse the
/// next live set and factorise ahead (a new thread per step) served their
/// blocks from fresh pages. The Xiaowan-like first 120 days with the next
/// live sets analysed on threads of their own: 174.7 against 188.0 s,
/// system time 69 against 84 s (28 Nov 2026). The threads allocate a few
/// large blocks each, so the arena's lock is not contended.
pub fn keep_freed_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: mallopt only sets the allocator's parameters; called before
    // any other thread exists.
    unsafe {
        libc::mallopt(libc::M_MMAP_THRESHOLD, MAPPED_FROM_BYTES as i32);
        libc::mallopt(libc::M_TRIM_THRESHOLD, i32::MAX);
        libc::mallopt(libc::M_TOP_PAD, 256 << 20);
        libc::mallopt(libc::M_ARENA_MAX, 1);
    }
}

/// Lowers the calling thread's scheduling priority to the least (nice
/// 19), so that it runs on the time the run's other threads leave idle.
/// Linux sets the nice value per thread; elsewhere nothing changes.
pub fn lower_this_threads_priority() {
    #[cfg(target_os = "linux")]
    // SAFETY: setpriority only changes the scheduling of the calling
    // thread (`who` 0 under PRIO_PROCESS is the caller on Linux).
    unsafe {
        libc::setpriority(libc::PRIO_PROCESS, 0, 19);
    }
}

/// Blocks of this size or more are mapped by glibc for themselves (the
/// largest threshold `mallopt` takes on 64-bit Linux) \[bytes\].
const MAPPED_FROM_BYTES: usize = 32 << 20;

/// Transparent huge pages come in this size on x86-64 and most aarch64
/// kernels \[bytes\]: the allocator advises them on blocks of this size or
/// more.
const HUGE_PAGE_BYTES: usize = 2 << 20;

/// The system allocator, asking the kernel to back every block of 2 MB or
/// more with transparent huge pages (`madvise(MADV_HUGEPAGE)` on the whole
/// huge pages inside it, close to what glibc's `glibc.malloc.hugetlb=1`
/// tunable does for its heap and mappings). The binary's global
/// allocator; no answer changes, only how the kernel backs the bytes.
///
/// Why: the large arch's mechanics allocates blocks of hundreds of MB to
/// GBs every day (each new live set's factor, K̃ with the grout springs,
/// the matrix of a refactorisation; glibc maps every block above 32 MB
/// afresh), and the kernel zeroes and maps each of their 4 KB pages on
/// first touch: 22,000 such faults a second on its late days, 13 % of the
/// run's samples in a profile on this virtual machine (of the faults, `perf
/// record -e page-faults`: 47 % copying K̃ into a new block, 30 % zeroing a
/// new factor). With huge pages a fault maps 2 MB, and the factorisation
/// and the solves, which stream through the factor, miss the TLB less.
/// Measured alone on the 2 cores (29 Nov 2026, `study perf
/// models/xiaowan_like.toml --days 40 --no-exact`, whole command): 78.4 s
/// against 99.3 s, 168,000 against 2.47M page faults, system time 18.9
/// against 31.4 s, the staged 40 days 47.8 against 59.9 s, the same peak
/// (5.0 GB); glibc's tunable 74.8 s and 57,000 faults; advising only the
/// mapped blocks (32 MB and more) 90.3 s and 277,000 faults. The demo's
/// blocks are a few MB: its whole construction is unchanged (108.9–112.4
/// against 109.0–110.4 s, alternated) and gives the same files. Where the
/// kernel has transparent huge pages off (`never`), the advice is ignored.
///
/// Blocks of 32 MB or more are its own mappings, kept when freed and
/// handed out again ([`large`]): on the virtual machines this runs on,
/// memory a process hands back goes back to the host within seconds and
/// comes back at 0.5 GB/s. Measured alone on the 2 cores, alternated twice
/// (5 Dec 2026): the large complete dam's step (`complete_step`) 72.1 and
/// 71.4 s against 75.9 and 74.6 s, peak 4.91–4.96 against 4.69 GB; the
/// large arch's days 856–862 8.3 and 8.6 s a step against 8.8 and 9.1 s,
/// peak 4.63–4.65 against 4.75–4.87 GB.
pub struct LargeBlocksOnHugePages;

// SAFETY: blocks below `KEPT_FROM_BYTES` are the system allocator's; the
// larger ones are whole mappings of their own (`large`), handed out to
// one owner at a time. The advice changes no byte of a block.
unsafe impl GlobalAlloc for LargeBlocksOnHugePages {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        if large::takes(layout) {
            return large::alloc(layout.size(), false);
        }
        let p = unsafe { System.alloc(layout) };
        advise_huge_pages(p, layout.size());
        p
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        if large::takes(layout) {
            return large::alloc(layout.size(), true);
        }
        let p = unsafe { System.alloc_zeroed(layout) };
        advise_huge_pages(p, layout.size());
        p
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        if large::takes(layout) {
            return unsafe { large::dealloc(ptr, layout.size()) };
        }
        unsafe { System.dealloc(ptr, layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        // SAFETY (all arms): `ptr` is this allocator's block of `layout`.
        let new_layout = unsafe { Layout::from_size_align_unchecked(new_size, layout.align()) };
        match (large::takes(layout), large::takes(new_layout)) {
            (true, true) => unsafe { large::realloc(ptr, layout.size(), new_size) },
            (false, false) => {
                let p = unsafe { System.realloc(ptr, layout, new_size) };
                advise_huge_pages(p, new_size);
                p
            }
            _ => {
                let p = unsafe { self.alloc(new_layout) };
                if !p.is_null() {
                    let n = layout.size().min(new_size);
                    unsafe { std::ptr::copy_nonoverlapping(ptr, p, n) };
                    unsafe { self.dealloc(ptr, layout) };
                }
                p
            }
        }
    }
}

mod large;

/// Advises huge pages on the whole huge pages inside the block `p` of
/// `size` bytes, when it is one of the large ones.
fn advise_huge_pages(p: *mut u8, size: usize) {
    if p.is_null() || size < HUGE_PAGE_BYTES {
        return;
    }
    let start = (p as usize).next_multiple_of(HUGE_PAGE_BYTES);
    let end = (p as usize + size) / HUGE_PAGE_BYTES * HUGE_PAGE_BYTES;
    if end <= start {
        return;
    }
    #[cfg(target_os = "linux")]
    // SAFETY: the range lies inside a block the allocator just handed out;
    // MADV_HUGEPAGE changes how its pages are backed, never its contents.
    // A kernel without transparent huge pages answers EINVAL: ignored.
    unsafe {
        libc::madvise(start as *mut libc::c_void, end - start, libc::MADV_HUGEPAGE);
    }
}

/// The machine's physical memory \[bytes\] (`MemTotal` of `/proc/meminfo`).
pub fn total_memory_bytes() -> Option<u64> {
    proc_field("/proc/meminfo", "MemTotal:").map(|kib| 1024 * kib)
}

/// The process's peak resident memory so far \[bytes\] (`VmHWM`).
pub fn peak_memory_bytes() -> Option<u64> {
    proc_field("/proc/self/status", "VmHWM:").map(|kib| 1024 * kib)
}

/// The CPU time this process has used so far, user and system over all
/// its threads \[s\] (`getrusage`): beside the wall time, how much of the
/// cores a run kept busy (`groutready study perf`).
pub fn cpu_seconds() -> Option<f64> {
    #[cfg(unix)]
    {
        let mut ru = std::mem::MaybeUninit::<libc::rusage>::zeroed();
        // SAFETY: getrusage writes the struct it is given and nothing else.
        if unsafe { libc::getrusage(libc::RUSAGE_SELF, ru.as_mut_ptr()) } != 0 {
            return None;
        }
        // SAFETY: getrusage succeeded, so it filled the struct.
        let ru = unsafe { ru.assume_init() };
        let s = |t: libc::timeval| t.tv_sec as f64 + 1e-6 * t.tv_usec as f64;
        Some(s(ru.ru_utime) + s(ru.ru_stime))
    }
    #[cfg(not(unix))]
    {
        None
    }
}

/// The kB figure of the line starting with `key` in a `/proc` file.
fn proc_field(path: &str, key: &str) -> Option<u64> {
    let text = std::fs::read_to_string(path).ok()?;
    let line = text.lines().find(|l| l.starts_with(key))?;
    line.split_whitespace().nth(1)?.parse().ok()
}

/// A lower bound of the memory a simulation of a mesh needs \[bytes\], to
/// refuse before building what cannot fit. Per element: the mesh and the
/// thermal tables (about 0.5 KB); with mechanics, the unit stiffness (4.6
/// KB), the Gauss data and the stress and creep state (about 8 KB more).
/// The sparse factor of the mechanics (3 dofs per node), or of a direct
/// thermal solve (1 per node): 8 bytes × 5 n^{4/3} entries (nested
/// dissection of a 3-D mesh; 5.5 measured on the Xiaowan-like matrix, 169M
/// entries for 410,904 dofs). Measured peaks are 2.5–4 times this bound
/// (the demo 376 MiB against 98 MiB; the Xiaowan-like complete step 6.4 GB
/// against 2.4 GiB), so a refusal is never wrong.
pub fn simulation_memory_lower_bound(
    elements: u64,
    nodes: u64,
    mechanics: bool,
    direct_thermal: bool,
) -> u64 {
    let factor = |dofs: f64| 8.0 * 5.0 * dofs.powf(4.0 / 3.0);
    let mut bytes = 512.0 * elements as f64;
    if mechanics {
        bytes += 12_800.0 * elements as f64 + factor(3.0 * nodes as f64);
    }
    if direct_thermal {
        bytes += factor(nodes as f64);
    }
    bytes.min(u64::MAX as f64) as u64
}

/// Bytes as GiB for messages.
pub fn gib(bytes: u64) -> f64 {
    bytes as f64 / (1u64 << 30) as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The bound stays below the peaks measured with `groutready study
    /// perf` (so a refusal is never wrong) and within a factor 4 of them (so
    /// it refuses what cannot fit).
    #[test]
    fn bound_is_below_measured_peaks() {
        // demo: 5,008 elements, 8,486 nodes, mechanics, direct thermal: 376 MiB
        let demo = simulation_memory_lower_bound(5_008, 8_486, true, true);
        assert!(
            gib(demo) < 376.0 / 1024.0 && gib(demo) > 376.0 / 1024.0 / 4.0,
            "{}",
            gib(demo)
        );
        // Xiaowan-like complete step: 100,716 elements, 136,968 nodes: 6.4 GB
        let xw = simulation_memory_lower_bound(100_716, 136_968, true, false);
        assert!(gib(xw) < 6.4 && gib(xw) > 6.4 / 4.0, "{}", gib(xw));
    }

    /// A block of 8 MB from the allocator lies in a mapping the kernel
    /// marks for huge pages (`hg` among its `VmFlags` in `/proc/self/smaps`);
    /// skipped where the kernel has no transparent huge pages.
    #[test]
    fn large_blocks_are_advised_huge_pages() {
        if !std::path::Path::new("/sys/kernel/mm/transparent_hugepage/enabled").exists() {
            eprintln!("skipped: no transparent huge pages on this machine");
            return;
        }
        let layout = Layout::from_size_align(8 << 20, 8).unwrap();
        // SAFETY: a non-zero layout, freed below with the same layout.
        let p = unsafe { LargeBlocksOnHugePages.alloc(layout) };
        assert!(!p.is_null());
        let inside = (p as usize).next_multiple_of(HUGE_PAGE_BYTES);
        let flags = vm_flags_at(inside).expect("a mapping holds the block");
        // SAFETY: allocated above with this layout.
        unsafe { LargeBlocksOnHugePages.dealloc(p, layout) };
        assert!(
            flags.split_whitespace().any(|f| f == "hg"),
            "VmFlags: {flags}"
        );
    }

    /// The `VmFlags` of the mapping of `/proc/self/smaps` holding `address`.
    fn vm_flags_at(address: usize) -> Option<String> {
        let smaps = std::fs::read_to_string("/proc/self/smaps").ok()?;
        let mut inside = false;
        for line in smaps.lines() {
            if let Some(flags) = line.strip_prefix("VmFlags:") {
                if inside {
                    return Some(flags.to_string());
                }
            } else if let Some((range, _)) = line.split_once(' ') {
                if let Some((lo, hi)) = range.split_once('-') {
                    if let (Ok(lo), Ok(hi)) =
                        (usize::from_str_radix(lo, 16), usize::from_str_radix(hi, 16))
                    {
                        inside = (lo..hi).contains(&address);
                    }
                }
            }
        }
        None
    }

    #[test]
    fn linux_reports_memory() {
        if cfg!(target_os = "linux") {
            assert!(total_memory_bytes().is_some_and(|b| b > 1 << 28));
            assert!(peak_memory_bytes().is_some_and(|b| b > 0));
        }
    }

    #[test]
    fn cpu_time_grows_with_work() {
        if cfg!(unix) {
            let before = cpu_seconds().expect("getrusage");
            let (mut x, mut after) = (0u64, before);
            let t = std::time::Instant::now();
            // spin until 20 ms of CPU are counted, however loaded the
            // machine; a clock that does not move fails at the cap
            while after - before <= 0.02 && t.elapsed().as_secs() < 10 {
                for _ in 0..10_000 {
                    x = std::hint::black_box(x.wrapping_mul(6364136223846793005).wrapping_add(1));
                }
                after = cpu_seconds().expect("getrusage");
            }
            assert!(after - before > 0.02, "{before} -> {after}");
        }
    }
}
