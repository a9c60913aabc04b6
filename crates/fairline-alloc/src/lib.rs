//! The `fairline` command's global allocator: the system allocator, with every large
//! block marked for transparent huge pages on Linux
//! (`madvise(MADV_HUGEPAGE)`).
//!
//! A command on a 450k-vertex mesh allocates about 130 MB in a few dozen
//! large blocks that it fills once. With 4 KiB pages the kernel maps and
//! clears them one page fault at a time: a quarter to a half of
//! `fairline info`'s wall time was spent in the kernel doing that
//! (`clear_page_erms`, `exc_page_fault`). With 2 MiB pages it takes 512×
//! fewer faults. The advice is only a hint: where the kernel's transparent
//! huge pages are off (`/sys/kernel/mm/transparent_hugepage/enabled` =
//! `never`) nothing changes, and on other systems the system allocator is
//! used as it is. Measured in BENCHMARKS.md ("Session 19 — quiet-machine
//! measurements").
//!
//! A crate of its own so that the library and the command keep
//! `#![forbid(unsafe_code)]`: this is the only unsafe code of the project.

use std::alloc::{GlobalAlloc, Layout, System};

/// The system allocator with huge-page advice for blocks of at least
/// [`LARGE_BLOCK`] bytes.
pub struct HugePageAdvice;

/// Blocks at least this large get the advice (several huge pages, so the
/// aligned interior that the advice covers is most of the block).
const LARGE_BLOCK: usize = 8 << 20;

/// Size of a transparent huge page on x86-64 and aarch64 with 4 KiB pages.
#[cfg(target_os = "linux")]
const HUGE_PAGE: usize = 2 << 20;

/// Advise the kernel to back the whole huge pages inside `[ptr, ptr+size)`
/// with huge pages. Errors are ignored: the advice changes speed, never
/// contents.
#[cfg(target_os = "linux")]
fn advise(ptr: *mut u8, size: usize) {
    let start = (ptr as usize).next_multiple_of(HUGE_PAGE);
    let end = (ptr as usize).saturating_add(size) / HUGE_PAGE * HUGE_PAGE;
    if end > start {
        // SAFETY: the range lies inside a block the allocator just handed
        // out; MADV_HUGEPAGE changes only how the kernel backs the pages,
        // never their contents or the mapping's protection.
        unsafe {
            libc::madvise(start as *mut libc::c_void, end - start, libc::MADV_HUGEPAGE);
        }
    }
}

#[cfg(not(target_os = "linux"))]
fn advise(_ptr: *mut u8, _size: usize) {}

// SAFETY: every method forwards to `System` with the caller's arguments
// unchanged; the advice only touches memory inside the returned block.
unsafe impl GlobalAlloc for HugePageAdvice {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        // SAFETY: forwarded unchanged (the caller upholds `alloc`'s contract).
        let ptr = unsafe { System.alloc(layout) };
        if !ptr.is_null() && layout.size() >= LARGE_BLOCK {
            advise(ptr, layout.size());
        }
        ptr
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        // SAFETY: forwarded unchanged.
        let ptr = unsafe { System.alloc_zeroed(layout) };
        if !ptr.is_null() && layout.size() >= LARGE_BLOCK {
            advise(ptr, layout.size());
        }
        ptr
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: forwarded unchanged.
        unsafe { System.dealloc(ptr, layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        // SAFETY: forwarded unchanged.
        let new = unsafe { System.realloc(ptr, layout, new_size) };
        if !new.is_null() && new_size >= LARGE_BLOCK {
            advise(new, new_size);
        }
        new
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Large blocks from the advising allocator keep their contents through
    /// writes, zeroed allocation and growth (the advice must never change
    /// data), small ones are untouched.
    #[test]
    fn large_blocks_keep_their_contents() {
        let a = HugePageAdvice;
        for size in [64, LARGE_BLOCK - 1, LARGE_BLOCK, 3 * LARGE_BLOCK + 12345] {
            let layout = Layout::from_size_align(size, 16).unwrap();
            // SAFETY: non-zero size; the block is written and read within
            // its bounds and freed with the same layout.
            unsafe {
                let z = a.alloc_zeroed(layout);
                assert!(!z.is_null());
                assert!(std::slice::from_raw_parts(z, size).iter().all(|&b| b == 0));
                a.dealloc(z, layout);
                let p = a.alloc(layout);
                assert!(!p.is_null());
                for i in (0..size).step_by(4093) {
                    *p.add(i) = (i % 251) as u8;
                }
                let grown = a.realloc(p, layout, 2 * size);
                assert!(!grown.is_null());
                for i in (0..size).step_by(4093) {
                    assert_eq!(*grown.add(i), (i % 251) as u8, "byte {i} of {size}");
                }
                a.dealloc(grown, Layout::from_size_align(2 * size, 16).unwrap());
            }
        }
    }
}
