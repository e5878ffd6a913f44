//! The FMU's log messages, kept so that an FMI call that fails can say why: the `fmi`
//! importer hands the FMU's logger callback to the `log` crate, and this logger keeps the
//! latest warnings and errors of each thread (an FMU instance logs on the thread that
//! calls it), until the driver takes them for an error.

use std::cell::RefCell;
use std::sync::Once;

/// Messages kept per thread; older ones are dropped.
const KEPT: usize = 16;

thread_local! {
    static MESSAGES: RefCell<Vec<String>> = const { RefCell::new(Vec::new()) };
}

/// The logger behind [`install`].
struct Keeper;

impl log::Log for Keeper {
    fn enabled(&self, metadata: &log::Metadata<'_>) -> bool {
        metadata.level() <= log::Level::Warn
    }

    fn log(&self, record: &log::Record<'_>) {
        if self.enabled(record.metadata()) {
            MESSAGES.with_borrow_mut(|m| {
                if m.len() == KEPT {
                    m.remove(0);
                }
                m.push(record.args().to_string());
            });
        }
    }

    fn flush(&self) {}
}

/// Installs the keeping logger, once; keeps nothing when the program installed another.
pub fn install() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        if log::set_logger(&Keeper).is_ok() {
            log::set_max_level(log::LevelFilter::Warn);
        }
    });
}

/// The warnings and errors this thread's FMU calls logged since the last call, oldest first.
pub fn take() -> Vec<String> {
    MESSAGES.with_borrow_mut(std::mem::take)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn warnings_and_errors_are_kept_per_thread_and_taken_once() {
        install();
        take();
        log::error!("first");
        log::info!("not kept");
        log::warn!("second");
        std::thread::spawn(|| log::error!("another thread"))
            .join()
            .expect("thread");
        assert_eq!(take(), ["first", "second"]);
        assert!(take().is_empty());
        for k in 0..KEPT + 3 {
            log::warn!("{k}");
        }
        let kept = take();
        assert_eq!(kept.len(), KEPT);
        assert_eq!(kept[0], "3");
    }
}
