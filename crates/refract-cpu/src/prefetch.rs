//! A software prefetch: the hint that lets a lookup that waits on memory (a `pvrr` map of
//! megabytes read along curves, a distance-map layer searched along a ray) ask for the cache
//! lines of the next pixels or samples before it reads them. The one `unsafe` block of the
//! crate.

/// Asks the CPU to bring `item`'s cache line into the caches (x86-64: `prefetcht0`;
/// elsewhere nothing). Reads nothing and changes nothing observable.
#[inline]
pub(crate) fn prefetch<T>(item: &T) {
    #[cfg(target_arch = "x86_64")]
    {
        use core::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
        // SAFETY: a prefetch is a hint: it reads nothing architecturally and cannot fault, and
        // the address is that of a live reference besides. SSE, which it needs, is part of
        // every x86-64 CPU.
        #[allow(unsafe_code)]
        unsafe {
            _mm_prefetch::<_MM_HINT_T0>(core::ptr::from_ref(item).cast());
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = item;
}
