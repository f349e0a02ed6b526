//! What the CLI prints: stdout through [`emit`] (a closed pipe is not an
//! error), errors on one line, progress bars, written files.

use surfmotion::util::errtext;

/// Writes to stdout; a closed pipe becomes [`OutputClosed`] instead of a panic.
pub fn emit(text: &str) -> anyhow::Result<()> {
    use std::io::Write;
    let mut out = std::io::stdout().lock();
    match out.write_all(text.as_bytes()).and_then(|_| out.flush()) {
        Ok(()) => Ok(()),
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => Err(OutputClosed.into()),
        // Named: "surfmotion: No space left on device" did not say where.
        Err(e) => Err(anyhow::anyhow!("writing to standard output: {e}")),
    }
}

/// `v` on stdout as pretty JSON and a newline ([`emit`]). A report whose
/// keys are printed sorted goes through `serde_json::to_value` first.
pub fn emit_json<T: serde::Serialize + ?Sized>(v: &T) -> anyhow::Result<()> {
    emit(&(serde_json::to_string_pretty(v)? + "\n"))
}

/// A report on stdout: `value()` as pretty JSON with `--json` (`json`),
/// else `text()` ([`emit`]); only the one asked for is computed.
pub fn report_with<J: serde::Serialize>(
    json: bool,
    value: impl FnOnce() -> anyhow::Result<J>,
    text: impl FnOnce() -> String,
) -> anyhow::Result<()> {
    match json {
        true => emit_json(&value()?),
        false => emit(&text()),
    }
}

/// [`report_with`] of `r` as serde writes it (fields in declaration order).
pub fn report<T: serde::Serialize + ?Sized>(
    json: bool,
    r: &T,
    text: impl FnOnce() -> String,
) -> anyhow::Result<()> {
    report_with(json, || Ok(r), text)
}

/// [`report_with`] of `r` through a `serde_json::Value`: its keys printed
/// sorted.
pub fn report_sorted<T: serde::Serialize + ?Sized>(
    json: bool,
    r: &T,
    text: impl FnOnce() -> String,
) -> anyhow::Result<()> {
    report_with(json, || Ok(serde_json::to_value(r)?), text)
}

/// A report written to `path` as pretty JSON, atomically (`--report`).
pub fn write_json<T: serde::Serialize + ?Sized>(
    path: &std::path::Path,
    v: &T,
) -> anyhow::Result<()> {
    let json = serde_json::to_string_pretty(v)?;
    Ok(surfmotion::util::fsutil::write_bytes_atomic(
        path,
        json.as_bytes(),
    )?)
}

/// `println!` through [`emit`].
#[macro_export]
macro_rules! outln {
    ($($t:tt)*) => { $crate::cli::emit(&format!("{}\n", format!($($t)*))) };
}

/// `eprintln!` that never panics: a line on stderr, dropped when stderr
/// is closed or full (`eprintln!` panicked there: `mesh convert A B
/// 2>&-` and every other verb that reports on stderr exited 2).
#[macro_export]
macro_rules! errln {
    ($($t:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stderr(), $($t)*);
    }};
}

/// An error and its causes on one line ([`errtext::one_line`]), the
/// library's option names printed as flags.
pub fn one_line(e: &anyhow::Error) -> String {
    super::flags::as_flags(&errtext::one_line(e.as_ref()))
}

/// Stdout was closed by the reader (e.g. `| head`): not an error.
#[derive(Debug, thiserror::Error)]
#[error("output closed")]
pub struct OutputClosed;

/// A progress bar on a terminal (hidden when stderr is not one).
pub fn progress(len: u64, what: &str) -> indicatif::ProgressBar {
    use std::io::IsTerminal;
    if !std::io::stderr().is_terminal() {
        return indicatif::ProgressBar::hidden();
    }
    let bar = indicatif::ProgressBar::new(len);
    bar.set_style(
        indicatif::ProgressStyle::with_template(&format!(
            "{{bar:40}} {{pos}}/{{len}} {what} {{elapsed}} (eta {{eta}}) {{msg}}"
        ))
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    bar
}

/// A spinner with a message and the elapsed time on a terminal (hidden
/// when stderr is not one), for work whose library call reports no
/// progress (`web export`: 10 s on samba with nothing on the screen;
/// `play`'s model build). Clear it with `finish_and_clear`.
pub fn spinner(what: &str) -> indicatif::ProgressBar {
    use std::io::IsTerminal;
    if !std::io::stderr().is_terminal() {
        return indicatif::ProgressBar::hidden();
    }
    let bar = indicatif::ProgressBar::new_spinner();
    bar.set_style(
        indicatif::ProgressStyle::with_template("{spinner} {msg} {elapsed}")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_spinner()),
    );
    bar.set_message(what.to_string());
    bar.enable_steady_tick(std::time::Duration::from_millis(120));
    bar
}

/// Progress bars for a build.
pub struct Bars(std::sync::Mutex<Option<indicatif::ProgressBar>>);

impl Bars {
    /// No bar yet.
    pub fn new() -> Bars {
        Bars(std::sync::Mutex::new(None))
    }
}

impl surfmotion::db::BuildProgress for Bars {
    fn start(&self, what: &str, total: u64) {
        if let Ok(mut b) = self.0.lock() {
            *b = Some(progress(total, what));
        }
    }
    fn advance(&self, k: u64) {
        if let Ok(b) = self.0.lock()
            && let Some(b) = b.as_ref()
        {
            b.inc(k);
        }
    }
    fn finish(&self) {
        if let Ok(mut b) = self.0.lock()
            && let Some(b) = b.take()
        {
            b.finish_and_clear();
        }
    }
}
