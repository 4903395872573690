//! The memory a run may use, estimates of what it needs from counts made before anything
//! is allocated, and fallible allocation for the large buffers.
//!
//! The limit is [`memory_limit`]: three quarters of the smaller of the process's
//! address-space limit (`ulimit -v`) and the machine's physical memory; the rest is left
//! to the program, its threads' stacks and the allocator's own reservations. A request
//! that would need more is refused with a sentence naming the count, the estimate and
//! the limit ([`check_bytes`]). The large per-pixel and per-texel buffers are allocated
//! through [`try_filled`], which returns an error where `vec![v; n]` would abort; and
//! [`GuardedAlloc`], installed as the global allocator of the command line, turns any
//! other failed allocation into a sentence and exit status 2 instead of an abort.
//!
//! The limit depends on the environment, never on the clock: results do not change with
//! it, only whether a run is refused.

use crate::error::{Error, Result};
use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::sync::OnceLock;

/// Share of the address-space limit or physical memory a run's estimate may take (the
/// remainder is headroom for code, stacks and allocator arenas), in quarters.
const USABLE_QUARTERS: u64 = 3;

/// The memory limit when neither the address-space limit nor the physical memory can be
/// read (64 GiB).
const FALLBACK_LIMIT: u64 = 64 << 30;

/// Bytes a run may allocate for its scene, images and maps (see the module doc).
pub fn memory_limit() -> u64 {
    static LIMIT: OnceLock<u64> = OnceLock::new();
    *LIMIT.get_or_init(|| {
        let mut total = physical_memory().unwrap_or(FALLBACK_LIMIT);
        if let Some(v) = address_space_limit() {
            total = total.min(v);
        }
        total / 4 * USABLE_QUARTERS
    })
}

/// The soft `RLIMIT_AS`, when one is set.
fn address_space_limit() -> Option<u64> {
    let mut r = libc::rlimit {
        rlim_cur: 0,
        rlim_max: 0,
    };
    // SAFETY: getrlimit writes the struct it is given and nothing else.
    let ok = unsafe { libc::getrlimit(libc::RLIMIT_AS, &mut r) } == 0;
    (ok && r.rlim_cur != libc::RLIM_INFINITY).then_some(r.rlim_cur)
}

/// Physical memory in bytes.
fn physical_memory() -> Option<u64> {
    // SAFETY: sysconf only reads system configuration.
    let (pages, size) = unsafe {
        (
            libc::sysconf(libc::_SC_PHYS_PAGES),
            libc::sysconf(libc::_SC_PAGESIZE),
        )
    };
    (pages > 0 && size > 0).then(|| pages as u64 * size as u64)
}

/// `n` bytes in MiB, rounded up, for messages.
pub fn mib(n: u64) -> u64 {
    n.div_ceil(1 << 20)
}

/// Refuses `bytes` above [`memory_limit`]: `what` names the request and its count
/// (e.g. "--width 8192 --height 8192: 67108864 pixels"), and the error gives the estimate
/// and the limit.
pub fn check_bytes(what: impl FnOnce() -> String, bytes: u64) -> Result<()> {
    let limit = memory_limit();
    if bytes > limit {
        return Err(Error::Limit(format!(
            "{} need about {} MiB, more than the {} MiB this process may use (3/4 of its address-space limit or of physical memory)",
            what(),
            mib(bytes),
            mib(limit)
        )));
    }
    Ok(())
}

/// The most runs (techniques and their parameter sweeps) one comparison may plan, on the
/// command line and in Python alike.
pub const MAX_RUNS: usize = 128;

/// Bytes a frame holds per pixel whatever the techniques: the camera pass's samples (68),
/// the rasterizer's depth and id tiles while they are assembled (16), the shaded images
/// and the animation frame (about 12), and the technique's per-pixel working set (afsm's
/// samples and lists, the largest, about 32).
pub const BYTES_PER_PIXEL: u64 = 128;

/// Bytes each result kept until the end of a run holds per pixel: its visibility (16),
/// with the error image and the comparison's working set in `compare` (16).
pub const RESULT_BYTES_PER_PIXEL: u64 = 32;

/// Refuses a `width × height` frame whose camera pass and `results` kept results (a
/// render keeps one; a comparison one per run and the reference's) would need more than
/// [`memory_limit`], before anything is rendered; `what` names where the size came from
/// (`"--width/--height"`, `"the camera"`).
pub fn check_frame(width: u32, height: u32, results: usize, what: &str) -> Result<()> {
    let pixels = width as u64 * height as u64;
    let per = BYTES_PER_PIXEL + RESULT_BYTES_PER_PIXEL * results as u64;
    check_bytes(
        || {
            format!(
                "a {width}x{height} image ({what}) with {results} result(s) kept: {pixels} pixels"
            )
        },
        pixels.saturating_mul(per),
    )
}

thread_local! {
    /// Depth of fallible allocations on this thread: while above zero, [`GuardedAlloc`]
    /// returns a failed allocation to its caller instead of ending the process.
    static FALLIBLE: Cell<u32> = const { Cell::new(0) };
}

/// Reserves room for `additional` more elements, returning an error instead of aborting
/// when the memory is not there.
pub fn try_reserve<T>(
    v: &mut Vec<T>,
    additional: usize,
) -> std::result::Result<(), std::collections::TryReserveError> {
    FALLIBLE.with(|f| f.set(f.get() + 1));
    let r = v.try_reserve_exact(additional);
    FALLIBLE.with(|f| f.set(f.get() - 1));
    r
}

/// `n` copies of `value`, or an error naming `what` and the size when the memory is not
/// there (where `vec![value; n]` would abort the process).
pub fn try_filled<T: Clone>(n: usize, value: T, what: &str) -> Result<Vec<T>> {
    let mut v = Vec::new();
    try_reserve(&mut v, n).map_err(|_| {
        Error::Limit(format!(
            "{what}: {n} elements of {} bytes ({} MiB) cannot be allocated; this process has too little memory for them",
            std::mem::size_of::<T>(),
            mib((n as u64).saturating_mul(std::mem::size_of::<T>() as u64))
        ))
    })?;
    v.resize(n, value);
    Ok(v)
}

/// The system allocator, except that an allocation that fails outside [`try_reserve`]
/// ends the process with one sentence on stderr and exit status 2 (the input asked for
/// more memory than there is) instead of an abort.
pub struct GuardedAlloc;

impl GuardedAlloc {
    #[cold]
    fn out_of_memory(size: usize) -> ! {
        // Nothing here may allocate: the message is built on the stack.
        let mut buf = [0u8; 256];
        let mut len = 0;
        let mut put = |s: &[u8]| {
            let n = s.len().min(buf.len() - len);
            buf[len..len + n].copy_from_slice(&s[..n]);
            len += n;
        };
        put(b"error: out of memory: an allocation of ");
        let mut digits = [0u8; 20];
        let mut k = digits.len();
        let mut m = mib(size as u64);
        loop {
            k -= 1;
            digits[k] = b'0' + (m % 10) as u8;
            m /= 10;
            if m == 0 {
                break;
            }
        }
        put(&digits[k..]);
        put(b" MiB failed; the scene or the requested sizes need more memory than this process may use\n");
        // SAFETY: writes a stack buffer to stderr, then ends the process without unwinding.
        unsafe {
            libc::write(2, buf.as_ptr().cast(), len);
            libc::_exit(2)
        }
    }

    fn check(ptr: *mut u8, size: usize) -> *mut u8 {
        if ptr.is_null() && FALLIBLE.with(|f| f.get()) == 0 {
            Self::out_of_memory(size);
        }
        ptr
    }
}

// SAFETY: every call forwards to the system allocator with the same arguments.
unsafe impl GlobalAlloc for GuardedAlloc {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        Self::check(System.alloc(layout), layout.size())
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        Self::check(System.alloc_zeroed(layout), layout.size())
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        Self::check(System.realloc(ptr, layout, new_size), new_size)
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        System.dealloc(ptr, layout)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_impossible_buffer_is_an_error_not_an_abort() {
        let e = try_filled(usize::MAX / 16, 0u64, "test buffer").unwrap_err();
        assert!(e.to_string().starts_with("test buffer: "), "{e}");
        assert_eq!(try_filled(3, 7u8, "small").unwrap(), vec![7, 7, 7]);
    }

    #[test]
    fn estimates_above_the_limit_are_refused_with_both_numbers() {
        assert!(check_bytes(|| "small".into(), 1 << 20).is_ok());
        let e = check_bytes(|| "--width 9 --height 9: 81 pixels".into(), u64::MAX).unwrap_err();
        let s = e.to_string();
        assert!(
            s.starts_with("--width 9 --height 9: 81 pixels need about "),
            "{s}"
        );
        assert!(s.contains(&format!("{} MiB this process", mib(memory_limit()))));
    }
}
