//! Third-party parsers (glTF, TOML, image decoders) run inside [`contain_panics`]: a panic in one of
//! them on a malformed file becomes an error naming the file instead of ending the process. Our own
//! checks run first so that none is expected; the fuzz test (`tests/fuzz_inputs.rs`) fails on any
//! panic contained here, which marks a check still missing.

use std::cell::RefCell;
use std::panic::{catch_unwind, AssertUnwindSafe, PanicHookInfo};
use std::sync::Once;

thread_local! {
    /// While this thread runs guarded work: the messages of the panics caught in it.
    static CAUGHT: RefCell<Option<Vec<String>>> = const { RefCell::new(None) };
}

static HOOK: Once = Once::new();

/// Installs, once, a panic hook that keeps a guarded thread's panic message for its error instead of
/// printing it, and leaves every other panic to the hook that was there before.
fn install_hook() {
    HOOK.call_once(|| {
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            let guarded = CAUGHT.with(|caught| match caught.try_borrow_mut().as_deref_mut() {
                Ok(Some(messages)) => {
                    messages.push(describe(info));
                    true
                }
                _ => false,
            });
            if !guarded {
                previous(info);
            }
        }));
    });
}

fn describe(info: &PanicHookInfo) -> String {
    let payload = info.payload();
    let message = payload.downcast_ref::<&str>().map(|s| s.to_string()).or_else(|| payload.downcast_ref::<String>().cloned());
    let message = crate::error::one_line(&message.unwrap_or_else(|| "a panic".to_owned()));
    match info.location() {
        Some(at) => format!("{message}, at {}:{}", at.file(), at.line()),
        None => message,
    }
}

/// Runs `work`; a panic inside it (on this thread) returns its message instead of unwinding further.
pub fn contain_panics<T>(work: impl FnOnce() -> T) -> Result<T, String> {
    install_hook();
    let outer = CAUGHT.with(|caught| caught.borrow_mut().replace(Vec::new()));
    let result = catch_unwind(AssertUnwindSafe(work));
    let messages = CAUGHT.with(|caught| std::mem::replace(&mut *caught.borrow_mut(), outer));
    result.map_err(|_| messages.and_then(|m| m.into_iter().next()).unwrap_or_else(|| "a panic".to_owned()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_contained_panic_returns_its_message_and_location() {
        let e = contain_panics(|| {
            let v: Vec<u8> = Vec::new();
            v[usize::from(v.is_empty()) * 3]
        })
        .unwrap_err();
        assert!(e.contains("index out of bounds") && e.contains("guard.rs"), "{e}");
        assert_eq!(contain_panics(|| 7), Ok(7));
    }

    #[test]
    fn guards_nest_and_threads_keep_their_own() {
        let inner = contain_panics(|| contain_panics(|| panic!("inner")).unwrap_err()).unwrap();
        assert!(inner.starts_with("inner"), "{inner}");
        let outer = contain_panics(|| {
            let _ = contain_panics(|| 1);
            panic!("outer")
        })
        .unwrap_err();
        assert!(outer.starts_with("outer"), "{outer}");
        let other = std::thread::spawn(|| contain_panics(|| panic!("other thread")).unwrap_err()).join().unwrap();
        assert!(other.starts_with("other thread"), "{other}");
    }
}
