//! Which instruction set the hottest loops run on, chosen at run time; and [`prefetch`], the
//! hint that brings a value into cache ahead of its read.
//!
//! The crate is compiled for the baseline x86-64 (SSE2), so that one build runs on every
//! x86-64 machine. On that baseline `f64::floor` is a library call, every instruction has
//! two operands (one of them overwritten, so values are copied around) and a vector holds
//! two doubles. Codes that are built for the machine they run on (LAMMPS and EDMD are built
//! with `-march=native`) do not pay for that. So a loop that dominates a run is compiled
//! twice, as numpy and simdjson do with their kernels: once for the baseline and once for
//! x86-64-v3 (AVX2, FMA, BMI1/2, LZCNT, MOVBE, SSE4.1/4.2: every x86-64 CPU since 2013–2015),
//! and [`v3`] picks the second where the CPU has it.
//!
//! **The same bits either way.** Rust never fuses a multiplication and an addition into an
//! FMA on its own (that needs `mul_add`, which is exact on either path) and never reorders
//! floating-point arithmetic to vectorise it, so the features change which instructions
//! compute each result, not the result. The tests run both versions of each loop on the
//! same state and compare the bits.
//!
//! `KINEMA_SIMD=baseline` in the environment keeps the baseline everywhere (read once, at
//! the first choice; any other value, or none, lets the CPU decide).
//!
//! A loop opts in by putting its body in an `#[inline(always)]` function and calling it
//! from two thin functions, the baseline one and one marked `#[target_feature(enable =
//! "avx,avx2,fma,bmi1,bmi2,lzcnt,movbe,popcnt,sse3,ssse3,sse4.1,sse4.2")]` (the features
//! [`v3`] checks), called only where [`v3`] holds; everything the body calls and wants on
//! the faster instructions must be `#[inline(always)]` too (a function that is not inlined
//! keeps its baseline code). Today: the event-driven loop (`collide/event_driven`).

use std::sync::OnceLock;

/// Whether the x86-64-v3 versions of the hottest loops may run here: the CPU has every
/// feature x86-64-v3 names and `KINEMA_SIMD` is not `baseline`. Decided once.
pub(crate) fn v3() -> bool {
    static CHOICE: OnceLock<bool> = OnceLock::new();
    *CHOICE.get_or_init(|| std::env::var("KINEMA_SIMD").map_or(true, |v| v != "baseline") && cpu_has_v3())
}

#[cfg(target_arch = "x86_64")]
fn cpu_has_v3() -> bool {
    use std::arch::is_x86_feature_detected as has;
    has!("avx")
        && has!("avx2")
        && has!("fma")
        && has!("bmi1")
        && has!("bmi2")
        && has!("lzcnt")
        && has!("movbe")
        && has!("popcnt")
        && has!("sse3")
        && has!("ssse3")
        && has!("sse4.1")
        && has!("sse4.2")
}

#[cfg(not(target_arch = "x86_64"))]
fn cpu_has_v3() -> bool {
    false
}

/// What the loops run on here, for reports: `"x86-64-v3"` or `"baseline"`.
pub fn level() -> &'static str {
    if v3() {
        "x86-64-v3"
    } else {
        "baseline"
    }
}

/// Asks the CPU to bring the cache line holding `value` into its caches, without waiting
/// (a hint: it changes no value, and on other architectures it does nothing). For loops that
/// read scattered values they know in advance, such as the neighbours' positions of a pair
/// pass, whose reads miss every cache once the particles outgrow them.
#[inline(always)]
pub(crate) fn prefetch<T>(value: &T) {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: a prefetch reads nothing and cannot fault; SSE is in the x86-64 baseline.
    unsafe {
        use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
        _mm_prefetch::<_MM_HINT_T0>((value as *const T).cast::<i8>());
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = value;
}
