//! Memory helpers of the hot loops: vectors backed by transparent huge pages where the
//! system allows it, and a cache prefetch.
//!
//! Arrays read at random places miss the TLB: the packer's event loop (events come in time
//! order, i.e. anywhere in the box: at 10⁶ particles its ~200 MB in 4 KiB pages miss the TLB
//! on almost every access, and each miss walks page tables that are themselves out of
//! cache) and the explicit heat step's gathers of the neighbours' temperatures (8 MB at 10⁶
//! particles). In 2 MiB pages the same arrays need a few hundred TLB entries. Linux hands
//! out such pages for ranges marked with `madvise(MADV_HUGEPAGE)` before they are first
//! touched (the usual setting of `/sys/kernel/mm/transparent_hugepage/enabled` is
//! `madvise`). Elsewhere these are plain vectors. Nothing here changes a value.

/// Collects `items` into a vector whose memory was advised for huge pages before the items
/// were written (only the whole 2 MiB pages inside it; small vectors are left alone).
pub fn huge_vec<T>(items: impl ExactSizeIterator<Item = T>) -> Vec<T> {
    let mut v = Vec::with_capacity(items.len());
    advise(v.as_mut_ptr() as usize, v.capacity() * std::mem::size_of::<T>());
    v.extend(items);
    v
}

/// `n` copies of `value` in a vector advised as in [`huge_vec`].
pub fn huge_filled<T: Clone>(n: usize, value: T) -> Vec<T> {
    huge_vec(std::iter::repeat_n(value, n))
}

/// A copy of `x` in a vector advised as in [`huge_vec`].
pub fn huge_copy<T: Copy>(x: &[T]) -> Vec<T> {
    huge_vec(x.iter().copied())
}

/// Asks the processor to start loading the cache line holding `*x` (no effect on results;
/// a no-op off x86-64).
#[inline(always)]
pub fn prefetch<T>(x: &T) {
    #[cfg(target_arch = "x86_64")]
    #[allow(unsafe_code)]
    // SAFETY: a prefetch is a hint that never faults and writes nothing; the address comes
    // from a live reference, and SSE (which the instruction needs) is part of x86-64.
    unsafe {
        std::arch::x86_64::_mm_prefetch::<{ std::arch::x86_64::_MM_HINT_T0 }>((x as *const T).cast());
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = x;
}

#[cfg(all(target_os = "linux", target_env = "gnu"))]
fn advise(addr: usize, bytes: usize) {
    // Smallest vector (bytes) worth advising: below two huge pages little of it is aligned.
    const MIN_BYTES: usize = 4 << 20;
    // Huge-page size assumed for the alignment of the advised range (bytes).
    const HUGE: usize = 2 << 20;
    if bytes < MIN_BYTES {
        return;
    }
    let start = addr.next_multiple_of(HUGE);
    let end = (addr + bytes) / HUGE * HUGE;
    if end > start {
        #[allow(unsafe_code)]
        // SAFETY: [start, end) lies inside one live allocation owned by the caller's vector
        // and is page aligned; MADV_HUGEPAGE only changes how the kernel backs the pages,
        // never their contents, and a refusal (error return) is harmless.
        unsafe {
            libc::madvise(start as *mut libc::c_void, end - start, libc::MADV_HUGEPAGE);
        }
    }
}

#[cfg(not(all(target_os = "linux", target_env = "gnu")))]
fn advise(_addr: usize, _bytes: usize) {}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn collects_like_a_vector() {
        let v = huge_vec((0..3_000_000u32).map(|i| i * 2));
        assert_eq!(v.len(), 3_000_000);
        assert_eq!(v[1_234_567], 2_469_134);
        assert_eq!(huge_filled(5, 7u8), vec![7u8; 5]);
        assert_eq!(huge_copy(&v[..]), v);
    }
}
