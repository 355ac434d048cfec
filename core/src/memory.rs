//! The memory a run will need against what the machine can give it, checked before the
//! setup allocates its tables: a run far beyond the machine stops with an error that names
//! the sizes and the scene key, where it would otherwise abort (a failed allocation) or be
//! killed by the kernel's out-of-memory killer, taking an FMU's host or a Python session
//! with it.
//!
//! The need is a lower bound: the particles times the bytes per particle measured at the
//! setup's peak (largest resident set, `/usr/bin/time -v`) on the Taylor bar at support 2,
//! less a fifth (2D 16 281 and 64 561 particles, 3D 26 257 particles on the O-grid):
//!
//! | rule | 2D measured (B / particle) | 2D bound | 3D measured | 3D bound |
//! |---|---|---|---|---|
//! | q2 | 1 920 - 2 350 | 1 500 | 17 900 | 14 000 |
//! | q4 | 3 200 - 3 630 | 2 500 | 32 100 | 25 000 |
//! | scni | 1 580 - 1 990 | 1 250 | 24 600 | 19 000 |
//!
//! A support below 2 spacings scales the bound by `(s / 2)^D` (fewer neighbours per
//! point); a larger one keeps it (support 3 took 1.75 times the memory of support 2 in 2D,
//! below `(3 / 2)^2`), as do heat, self-contact and history, which only add. So a run that
//! is refused could not have fitted, and one that passes may still be close.
//!
//! What the machine can give (Linux; elsewhere nothing is checked): the memory available
//! (`MemAvailable` and `SwapFree` of `/proc/meminfo`) against the bound, and the address
//! space left under the process's limit (`ulimit -v`: the soft `Max address space` of
//! `/proc/self/limits` less `VmSize` of `/proc/self/status`) against
//! [`ADDRESS_SPACE_PER_RESIDENT`] times it.

use crate::error::{Error, Result};
use crate::math::Real;
use crate::scene::IntegrationRule;

/// Lower bound of the bytes per particle of a run of `dims` dimensions with `rule` at a
/// support of `support` spacings (the geometric mean over the directions), from the table
/// of the module's doc.
pub fn bytes_per_particle(dims: usize, rule: IntegrationRule, support: Real) -> Real {
    let at_two = match (dims, rule) {
        (2, IntegrationRule::Q2) => 1_500.0,
        (2, IntegrationRule::Q4) => 2_500.0,
        (2, IntegrationRule::Scni) => 1_250.0,
        (_, IntegrationRule::Q2) => 14_000.0,
        (_, IntegrationRule::Q4) => 25_000.0,
        (_, IntegrationRule::Scni) => 19_000.0,
    };
    at_two * (support / 2.0).min(1.0).powi(dims as i32)
}

/// The value in kB of the line of `/proc/meminfo` or `/proc/self/status` text `text` named
/// `name` (`MemAvailable:   123456 kB`), in bytes.
fn kb_field(text: &str, name: &str) -> Option<u64> {
    text.lines()
        .find_map(|l| l.strip_prefix(name)?.strip_prefix(':'))
        .and_then(|rest| rest.split_whitespace().next()?.parse::<u64>().ok())
        .map(|kb| kb * 1024)
}

/// The soft limit of the `Max address space` line of `/proc/self/limits` text, in bytes;
/// `None` when unlimited.
fn address_space_limit(limits: &str) -> Option<u64> {
    limits
        .lines()
        .find_map(|l| l.strip_prefix("Max address space"))
        .and_then(|rest| rest.split_whitespace().next()?.parse::<u64>().ok())
}

/// What this process can still have (bytes): the memory available with the free swap,
/// and the address space left under its limit; each `None` when unknown or unlimited.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Available {
    /// `MemAvailable + SwapFree` (B).
    pub memory: Option<u64>,
    /// The soft address-space limit less the process's size `VmSize` (B).
    pub address_space: Option<u64>,
}

/// Address space per byte resident at the setup's peak (-), a lower bound: `VmPeak / VmHWM`
/// measured 1.39-1.50 (2D q2 and q4 at 401 401 particles, 3D q2 at 253 461), the allocator's
/// arenas, the threads' stacks and a growing array's old and new buffers.
pub const ADDRESS_SPACE_PER_RESIDENT: Real = 1.3;

/// [`Available`] from the texts of `/proc/meminfo`, `/proc/self/limits` and
/// `/proc/self/status`.
fn available_from(meminfo: &str, limits: &str, status: &str) -> Available {
    Available {
        memory: kb_field(meminfo, "MemAvailable")
            .map(|m| m + kb_field(meminfo, "SwapFree").unwrap_or(0)),
        address_space: address_space_limit(limits)
            .map(|lim| lim.saturating_sub(kb_field(status, "VmSize").unwrap_or(0))),
    }
}

/// What this process can still have ([`available_from`] on this machine's `/proc`; nothing
/// known where it cannot be read).
pub fn available() -> Available {
    let read = |p: &str| std::fs::read_to_string(p).unwrap_or_default();
    available_from(
        &read("/proc/meminfo"),
        &read("/proc/self/limits"),
        &read("/proc/self/status"),
    )
}

/// Gigabytes of `bytes`, for messages.
fn gb(bytes: Real) -> Real {
    bytes / 1e9
}

/// Refuses a run of `particles` particles that needs at least `per_particle` bytes each
/// resident ([`bytes_per_particle`]) when that is more than the memory `have` holds, or
/// [`ADDRESS_SPACE_PER_RESIDENT`] times it more than the address space left, naming the
/// scene key `key` that sets the particles and `what` the run is (`q2 in 3d`).
pub fn check_with(
    particles: usize,
    per_particle: Real,
    have: Available,
    key: &str,
    what: &str,
) -> Result<()> {
    let need = particles as Real * per_particle;
    let refuse = |need: Real, have: u64, of: &str| {
        Err(Error::Memory(format!(
            "`{key}`: {particles} particles ({what}) need at least {:.1} GB of {of}, more than the {:.1} GB this process can have: fewer particles",
            gb(need),
            gb(have as Real)
        )))
    };
    match have {
        Available {
            memory: Some(m), ..
        } if need > m as Real => refuse(need, m, "memory (free memory and swap)"),
        Available {
            address_space: Some(a),
            ..
        } if need * ADDRESS_SPACE_PER_RESIDENT > a as Real => refuse(
            need * ADDRESS_SPACE_PER_RESIDENT,
            a,
            "address space (its limit, `ulimit -v`)",
        ),
        _ => Ok(()),
    }
}

/// [`check_with`] against this machine ([`available`]).
pub fn check(
    particles: usize,
    dims: usize,
    rule: IntegrationRule,
    support: Real,
    key: &str,
) -> Result<()> {
    let what = format!("{rule:?} in {dims}D").to_lowercase();
    check_with(
        particles,
        bytes_per_particle(dims, rule, support),
        available(),
        key,
        &what,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    const MEMINFO: &str = "MemTotal:       24000000 kB\nMemFree:         1000000 kB\nMemAvailable:   20000000 kB\nSwapTotal:        512000 kB\nSwapFree:         500000 kB\n";
    const LIMITS: &str = "Limit                     Soft Limit           Hard Limit           Units     \nMax cpu time              unlimited            unlimited            seconds   \nMax address space         3000000000           unlimited            bytes     \nMax file locks            unlimited            unlimited            locks     \n";
    const STATUS: &str =
        "Name:\trkforge\nVmPeak:\t  200000 kB\nVmSize:\t  100000 kB\nVmRSS:\t   20000 kB\n";

    /// The memory available is `MemAvailable + SwapFree`; the address space left is the soft
    /// limit less the process's size; unreadable or unlimited is unknown.
    #[test]
    fn what_a_process_can_have_is_read_from_proc() {
        let unlimited = LIMITS.replace("3000000000", "unlimited");
        assert_eq!(
            available_from(MEMINFO, &unlimited, STATUS),
            Available {
                memory: Some(20_500_000 * 1024),
                address_space: None
            }
        );
        assert_eq!(
            available_from(MEMINFO, LIMITS, STATUS).address_space,
            Some(3_000_000_000 - 100_000 * 1024)
        );
        assert_eq!(available_from("", "", ""), Available::default());
    }

    /// A run past the memory, or past the address space left at 1.3 times its memory, is
    /// refused, naming the key, the particles and both sizes; one within both, or on a
    /// machine that cannot tell, is not.
    #[test]
    fn a_run_beyond_the_machine_is_refused_by_key() {
        let per = bytes_per_particle(3, IntegrationRule::Q2, 2.0);
        assert_eq!(per, 14_000.0);
        let memory = |m| Available {
            memory: Some(m),
            address_space: None,
        };
        let e = check_with(
            4_000_000,
            per,
            memory(24_000_000_000),
            "workpiece.cells",
            "q2 in 3d",
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("`workpiece.cells`")
                && e.contains("4000000 particles (q2 in 3d)")
                && e.contains("56.0 GB of memory")
                && e.contains("24.0 GB"),
            "{e}"
        );
        assert!(check_with(1_000_000, per, memory(24_000_000_000), "k", "w").is_ok());
        assert!(check_with(4_000_000, per, Available::default(), "k", "w").is_ok());
        // 253 461 particles of 3D q2 under `ulimit -v 4000000` (kB): 3.5 GB resident fits in
        // 4.1 GB, 4.6 GB of address space does not (the run aborted at 7.0 GB VmPeak).
        let limited = Available {
            memory: Some(24_000_000_000),
            address_space: Some(4_096_000_000),
        };
        let e = check_with(253_461, per, limited, "workpiece.cells", "q2 in 3d")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("4.6 GB of address space") && e.contains("4.1 GB"),
            "{e}"
        );
    }

    /// A smaller support lowers the bound by `(s / 2)^D`; a larger one keeps it.
    #[test]
    fn the_bound_follows_a_smaller_support_only() {
        let q4 = |s| bytes_per_particle(2, IntegrationRule::Q4, s);
        assert_eq!(q4(2.0), 2_500.0);
        assert_eq!(q4(3.0), 2_500.0);
        assert_eq!(q4(1.0), 625.0);
        assert_eq!(
            bytes_per_particle(3, IntegrationRule::Scni, 1.0),
            19_000.0 / 8.0
        );
    }
}
