//! Ctrl-C (SIGINT) and SIGTERM through signal-hook: the first asks the run to stop, a second
//! exits at once with 128 + its number.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

/// Which signals came: set by signal-hook's handlers, which only store to atomics.
struct Signals {
    interrupt: Arc<AtomicBool>,
    terminate: Arc<AtomicBool>,
    any: Arc<AtomicBool>,
}

static SIGNALS: std::sync::OnceLock<Signals> = std::sync::OnceLock::new();

/// Whether Ctrl-C (SIGINT) or SIGTERM came.
pub(crate) fn interrupted() -> bool {
    SIGNALS.get().is_some_and(|s| s.any.load(Ordering::SeqCst))
}

/// The exit code for the signal that came: 128 + its number (130 SIGINT, 143 SIGTERM).
pub(crate) fn interrupt_code() -> u8 {
    match signal_name() {
        "SIGTERM" => 143,
        _ => 130,
    }
}

pub(crate) fn signal_name() -> &'static str {
    let term = SIGNALS
        .get()
        .is_some_and(|s| s.terminate.load(Ordering::SeqCst));
    let int = SIGNALS
        .get()
        .is_some_and(|s| s.interrupt.load(Ordering::SeqCst));
    match (term, int) {
        (true, false) => "SIGTERM",
        _ => "SIGINT",
    }
}

/// The first Ctrl-C or SIGTERM asks the run to stop: frames in flight are cancelled, the
/// finished ones stay. A second one exits at once with 128 + its number (a later run removes
/// any temporary file that leaves behind). Installed once per process.
pub(crate) fn install_interrupt_handler() {
    use signal_hook::consts::{SIGINT, SIGTERM};
    use signal_hook::flag;
    SIGNALS.get_or_init(|| {
        let s = Signals {
            interrupt: Arc::new(AtomicBool::new(false)),
            terminate: Arc::new(AtomicBool::new(false)),
            any: Arc::new(AtomicBool::new(false)),
        };
        for (signal, seen) in [(SIGINT, &s.interrupt), (SIGTERM, &s.terminate)] {
            // Handlers run in the order registered: the exit comes first, so it sees only a
            // signal that came before this one.
            let registered =
                flag::register_conditional_shutdown(signal, 128 + signal, Arc::clone(&s.any))
                    .and_then(|_| flag::register(signal, Arc::clone(seen)))
                    .and_then(|_| flag::register(signal, Arc::clone(&s.any)));
            if let Err(e) = registered {
                crate::console::warning(&format!("rayreel: cannot handle signal {signal}: {e}"));
            }
        }
        s
    });
}
