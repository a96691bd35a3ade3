//! The real-time mode of the runtime thread: a real-time scheduling policy and priority
//! (SCHED_FIFO or SCHED_RR), locked memory with the stack and a heap reserve faulted in
//! beforehand, and one CPU the runtime thread is pinned to while every other thread of the
//! process (ADS server, web view, program loader, logger) is kept off it. What every cyclic
//! runtime on a PC offers, and what Linux's own latency reference, `cyclictest` of rt-tests,
//! does with `-p 80 -m -a CPU` (rt-tests' cyclictest(8) manual page).
//!
//! Each part that the system refuses (no CAP_SYS_NICE nor RLIMIT_RTPRIO for the policy, no
//! CAP_IPC_LOCK nor RLIMIT_MEMLOCK for the lock, a CPU outside the process's set) is one
//! line in [`Entered::refused`]; the run goes on without it unless `required` asks to stop.
//!
//! System calls: `rustix` (affinity, `mlockall`, thread ids) and `thread-priority` (the
//! scheduling policy, which rustix does not wrap), so the crate keeps no `unsafe` of its own.

pub use crate::vocab::realtime::{Policy, RealtimeConfig, PRIORITIES};

/// Bytes of stack touched before the run, so the runtime thread's stack is faulted in and
/// locked: 256 KiB, far above the deepest tick (the program's subroutine nesting is bounded
/// by `decoder.max_subroutine_depth`).
const STACK_RESERVE_BYTES: usize = 256 * 1024;

/// Bytes of heap allocated, touched and freed before the run, so the allocator holds that
/// much already-mapped, locked memory for the ticks' allocations: 16 MiB.
const HEAP_RESERVE_BYTES: usize = 16 * 1024 * 1024;

/// The command line's real-time options, shared by `serve`, `run --realtime`,
/// `soak --realtime` and `bench`; each overrides runtime.toml's `[realtime]` key of its name.
#[derive(Debug, Clone, Default, clap::Args)]
pub struct RealtimeArgs {
    /// Real-time mode: run the runtime thread at this real-time priority (1-99) under
    /// --rt-policy (runtime.toml `realtime.priority`).
    #[arg(long, value_name = "PRIORITY", value_parser = clap::value_parser!(u8).range(1..=99))]
    pub rt_priority: Option<u8>,
    /// Real-time mode: the scheduling policy of --rt-priority (runtime.toml `realtime.policy`).
    #[arg(long, value_enum, value_name = "POLICY")]
    pub rt_policy: Option<Policy>,
    /// Real-time mode: pin the runtime thread to this CPU and keep the other threads off it
    /// (runtime.toml `realtime.cpu`).
    #[arg(long, value_name = "CPU")]
    pub rt_cpu: Option<usize>,
    /// Real-time mode: lock all memory, the stack and a heap reserve faulted in beforehand
    /// (runtime.toml `realtime.lock_memory`).
    #[arg(long)]
    pub rt_lock_memory: bool,
    /// Real-time mode: exit (code 5) when the system refuses a part of it, instead of a
    /// warning and running without it (runtime.toml `realtime.required`).
    #[arg(long)]
    pub rt_required: bool,
}

impl RealtimeArgs {
    /// The mode: `base` (runtime.toml's `[realtime]`) with every option given here over it.
    pub fn over(&self, base: &RealtimeConfig) -> RealtimeConfig {
        RealtimeConfig {
            policy: self.rt_policy.unwrap_or(base.policy),
            priority: self.rt_priority.or(base.priority),
            cpu: self.rt_cpu.or(base.cpu),
            lock_memory: self.rt_lock_memory || base.lock_memory,
            required: self.rt_required || base.required,
        }
    }

    /// Whether any option was given.
    pub fn any(&self) -> bool {
        self.rt_priority.is_some()
            || self.rt_policy.is_some()
            || self.rt_cpu.is_some()
            || self.rt_lock_memory
            || self.rt_required
    }
}

/// What [`enter`] did: the parts applied and one line for each part the system refused.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Entered {
    pub applied: Vec<String>,
    pub refused: Vec<String>,
    /// The parts that apply (the refused ones left out): what a reference measured beside
    /// the runtime (the bench's cyclictest) is given.
    pub effective: RealtimeConfig,
}

impl Entered {
    /// The one line a command prints: what runs, or nothing when the mode is off.
    pub fn summary(&self) -> Option<String> {
        (!self.applied.is_empty()).then(|| format!("real-time mode: {}", self.applied.join(", ")))
    }
}

/// Put the calling thread (the runtime thread, right before its first tick, after every other
/// thread of the process has been started) into the real-time mode `cfg`: memory first (the
/// locked, faulted-in pages are then the runtime's), then the CPU (every other thread moved
/// off it, this one onto it), then the policy. A refused part is a line in
/// [`Entered::refused`] and the others still apply.
pub fn enter(cfg: &RealtimeConfig) -> Entered {
    apply(cfg, Others::Moved)
}

/// [`enter`] for a command: nothing when `mode` is off; else each refusal said through `say`
/// as `ncchannel COMMAND: real-time mode: …`; with `required`, a refusal is the error (said
/// too) the command stops with. The mode's own line ([`Entered::summary`]) is the caller's.
pub fn enter_saying(
    mode: &RealtimeConfig,
    command: &str,
    mut say: impl FnMut(std::fmt::Arguments<'_>),
) -> Result<Entered, String> {
    if !mode.is_on() {
        return Ok(Entered::default());
    }
    let done = enter(mode);
    for line in &done.refused {
        say(format_args!("ncchannel {command}: {line}"));
    }
    if mode.required && !done.refused.is_empty() {
        let msg = format!(
            "ncchannel {command}: --rt-required: stopping, the real-time mode is incomplete"
        );
        say(format_args!("{msg}"));
        return Err(msg);
    }
    Ok(done)
}

/// Whether [`apply`] moves the process's other threads off the pinned CPU.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Others {
    Moved,
    /// Left where they are (the unit tests, whose other threads are the test harness's).
    #[cfg_attr(not(test), allow(dead_code))]
    Left,
}

fn apply(cfg: &RealtimeConfig, others: Others) -> Entered {
    let mut done = Entered {
        effective: RealtimeConfig {
            policy: cfg.policy,
            required: cfg.required,
            ..RealtimeConfig::default()
        },
        ..Entered::default()
    };
    if cfg.lock_memory {
        match sys::lock_memory() {
            Ok(()) => {
                prefault();
                done.effective.lock_memory = true;
                done.applied.push("memory locked".into());
            }
            Err(e) => done.refused.push(format!(
                "real-time mode: memory lock refused ({e}); it needs CAP_IPC_LOCK or `ulimit -l unlimited`; running with unlocked memory"
            )),
        }
    }
    if let Some(cpu) = cfg.cpu {
        match sys::pin(cpu, others == Others::Moved) {
            Ok(()) => {
                done.effective.cpu = Some(cpu);
                done.applied.push(format!("CPU {cpu}"));
            }
            Err(e) => done.refused.push(format!(
                "real-time mode: pinning to CPU {cpu} refused ({e}); running on any CPU"
            )),
        }
    }
    if let Some(p) = cfg.priority {
        match sys::set_policy(cfg.policy, p) {
            Ok(()) => {
                done.effective.priority = Some(p);
                done.applied.push(format!("{} {p}", cfg.policy.name()));
            }
            Err(e) => done.refused.push(format!(
                "real-time mode: {} priority {p} refused ({e}); it needs CAP_SYS_NICE or `ulimit -r {p}`; running at normal priority",
                cfg.policy.name()
            )),
        }
    }
    done
}

/// Fault in a stack reserve and a heap reserve, so the first ticks find their pages mapped
/// and (with the memory locked) resident. The heap reserve is allocated twice: glibc's malloc
/// serves the first large block with its own mapping and, freeing it, raises its threshold,
/// so the second comes from the heap and stays there, free, after the drop.
fn prefault() {
    let stack = [0u8; STACK_RESERVE_BYTES];
    std::hint::black_box(&stack);
    for _ in 0..2 {
        let heap = vec![1u8; HEAP_RESERVE_BYTES];
        std::hint::black_box(&heap);
    }
}

/// The scheduling of one thread as the kernel reports it in `/proc/self/task/TID/stat`
/// (proc(5)): for the tests and the bench's read-back.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ThreadSched {
    /// The policy number: 0 SCHED_OTHER, 1 SCHED_FIFO, 2 SCHED_RR (sched(7)).
    pub policy: u32,
    /// The real-time priority (0 under SCHED_OTHER).
    pub rt_priority: u32,
    /// Minor page faults of the thread so far.
    pub minor_faults: u64,
}

impl ThreadSched {
    /// Read from the text of a `stat` file: the fields after the command's closing `)`.
    pub fn parse(stat: &str) -> Option<ThreadSched> {
        let rest = &stat[stat.rfind(')')? + 1..];
        // `rest` starts at field 3 (state): field n is rest's word n - 3.
        let fields: Vec<&str> = rest.split_whitespace().collect();
        let field = |n: usize| fields.get(n - 3).and_then(|f| f.parse::<u64>().ok());
        Some(ThreadSched {
            minor_faults: field(10)?,
            rt_priority: u32::try_from(field(40)?).ok()?,
            policy: u32::try_from(field(41)?).ok()?,
        })
    }

    /// The calling thread's.
    pub fn current() -> Option<ThreadSched> {
        let text = std::fs::read_to_string("/proc/thread-self/stat").ok()?;
        ThreadSched::parse(&text)
    }
}

/// The CPUs the calling thread may run on (empty where the system does not say).
pub fn current_affinity() -> Vec<usize> {
    sys::affinity()
}

#[cfg(target_os = "linux")]
mod sys {
    use rustix::process::Pid;
    use rustix::thread::{sched_getaffinity, sched_setaffinity, CpuSet};
    use thread_priority::{
        set_thread_priority_and_policy, thread_native_id, RealtimeThreadSchedulePolicy,
        ThreadPriority, ThreadPriorityValue, ThreadSchedulePolicy,
    };

    use super::Policy;

    pub(super) fn lock_memory() -> Result<(), String> {
        use rustix::mm::{mlockall, MlockAllFlags};
        mlockall(MlockAllFlags::CURRENT | MlockAllFlags::FUTURE).map_err(|e| e.to_string())
    }

    pub(super) fn affinity() -> Vec<usize> {
        sched_getaffinity(None).map_or_else(
            |_| Vec::new(),
            |set| (0..CpuSet::MAX_CPU).filter(|&c| set.is_set(c)).collect(),
        )
    }

    /// Every other thread of the process onto the process's CPUs but `cpu`, then this one
    /// onto `cpu`. Threads started later by another thread inherit its set (sched_setaffinity(2)).
    pub(super) fn pin(cpu: usize, move_others: bool) -> Result<(), String> {
        let all = sched_getaffinity(None).map_err(|e| e.to_string())?;
        if cpu >= CpuSet::MAX_CPU || !all.is_set(cpu) {
            let have: Vec<String> = affinity().iter().map(ToString::to_string).collect();
            return Err(format!(
                "CPU {cpu} is not one of this process's CPUs {}",
                have.join(" ")
            ));
        }
        let mut others = all;
        others.unset(cpu);
        if others.count() == 0 {
            return Err(format!(
                "CPU {cpu} is the only CPU: the other threads cannot be kept off it"
            ));
        }
        if move_others {
            let me = rustix::thread::gettid();
            for tid in other_threads(me) {
                // A thread that ended meanwhile is no longer there to move.
                let _ = sched_setaffinity(Some(tid), &others);
            }
        }
        let mut one = CpuSet::new();
        one.set(cpu);
        sched_setaffinity(None, &one).map_err(|e| e.to_string())
    }

    /// The process's threads but `me`, from /proc/self/task (proc(5)).
    fn other_threads(me: Pid) -> Vec<Pid> {
        let Ok(dir) = std::fs::read_dir("/proc/self/task") else {
            return Vec::new();
        };
        dir.filter_map(|e| e.ok()?.file_name().to_str()?.parse::<i32>().ok())
            .filter_map(Pid::from_raw)
            .filter(|&t| t != me)
            .collect()
    }

    pub(super) fn set_policy(policy: Policy, priority: u8) -> Result<(), String> {
        let value = ThreadPriorityValue::try_from(priority).map_err(|e| e.to_string())?;
        let policy = ThreadSchedulePolicy::Realtime(match policy {
            Policy::Fifo => RealtimeThreadSchedulePolicy::Fifo,
            Policy::Rr => RealtimeThreadSchedulePolicy::RoundRobin,
        });
        set_thread_priority_and_policy(
            thread_native_id(),
            ThreadPriority::Crossplatform(value),
            policy,
        )
        .map_err(|e| match e {
            thread_priority::Error::OS(code) => std::io::Error::from_raw_os_error(code).to_string(),
            other => other.to_string(),
        })
    }
}

#[cfg(not(target_os = "linux"))]
mod sys {
    use super::Policy;

    const UNSUPPORTED: &str = "not supported on this system";

    pub(super) fn lock_memory() -> Result<(), String> {
        Err(UNSUPPORTED.into())
    }
    pub(super) fn affinity() -> Vec<usize> {
        Vec::new()
    }
    pub(super) fn pin(_cpu: usize, _move_others: bool) -> Result<(), String> {
        Err(UNSUPPORTED.into())
    }
    pub(super) fn set_policy(_policy: Policy, _priority: u8) -> Result<(), String> {
        Err(UNSUPPORTED.into())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stat_fields_are_read_after_the_command() {
        // A command with a space and a parenthesis, as a thread name may have.
        let mut fields: Vec<String> = (3..=52).map(|n| n.to_string()).collect();
        fields[10 - 3] = "1234".into();
        fields[40 - 3] = "80".into();
        fields[41 - 3] = "1".into();
        let stat = format!("42 (nc (rt) 1) {}", fields.join(" "));
        let s = ThreadSched::parse(&stat).unwrap();
        assert_eq!((s.policy, s.rt_priority, s.minor_faults), (1, 80, 1234));
        assert_eq!(ThreadSched::parse("42 (x) S 1 2"), None);
    }

    #[test]
    fn options_override_the_file() {
        let file = RealtimeConfig {
            policy: Policy::Rr,
            priority: Some(10),
            cpu: Some(0),
            lock_memory: true,
            required: false,
        };
        let args = RealtimeArgs {
            rt_priority: Some(80),
            rt_cpu: Some(1),
            rt_required: true,
            ..RealtimeArgs::default()
        };
        let m = args.over(&file);
        assert_eq!(m.policy, Policy::Rr);
        assert_eq!(
            (m.priority, m.cpu, m.lock_memory, m.required),
            (Some(80), Some(1), true, true)
        );
        assert_eq!(m.describe(), "SCHED_RR 80, CPU 1, memory locked");
        assert!(!RealtimeConfig::default().is_on());
        assert_eq!(
            RealtimeArgs::default()
                .over(&RealtimeConfig::default())
                .describe(),
            "off"
        );
    }

    /// Where the privilege exists (root, CAP_SYS_NICE or a high enough RLIMIT_RTPRIO) the
    /// thread reads back SCHED_FIFO 80 on its one CPU; where it does not, the refusal is one
    /// line naming the policy and what it needs, and the thread keeps running as before.
    #[test]
    fn policy_and_pinning_apply_or_say_why_not() {
        let handle = std::thread::spawn(|| {
            let cpu = *current_affinity().last().unwrap_or(&0);
            let cfg = RealtimeConfig {
                priority: Some(80),
                cpu: Some(cpu),
                ..RealtimeConfig::default()
            };
            let before = ThreadSched::current();
            let done = apply(&cfg, Others::Left);
            (
                cpu,
                done,
                before,
                ThreadSched::current(),
                current_affinity(),
            )
        });
        let (cpu, done, before, after, affinity) = handle.join().unwrap();
        let after = after.expect("/proc/thread-self/stat readable");
        if done.refused.is_empty() {
            assert_eq!((after.policy, after.rt_priority), (1, 80), "{done:?}");
            assert_eq!(affinity, vec![cpu]);
            assert_eq!(
                done.applied,
                vec![format!("CPU {cpu}"), "SCHED_FIFO 80".to_string()]
            );
        } else {
            for line in &done.refused {
                assert!(
                    line.starts_with("real-time mode: ") && !line.contains('\n'),
                    "{line}"
                );
            }
            let policy_refused = done
                .refused
                .iter()
                .any(|l| l.contains("SCHED_FIFO priority 80 refused"));
            assert_eq!(policy_refused, after.policy == 0, "{done:?}");
            assert_eq!(before.map(|b| b.policy), Some(0));
        }
    }
}
