//! Where the library's log events go: warnings on stderr, notices of
//! the jobs layer as plain lines, a result's plausibility warnings left
//! to the summary that prints them.

/// The module whose warnings are a result's plausibility warnings
/// ([`surfmotion::tools::eval::Plausibility`]'s `logged`).
const PLAUSIBILITY_MODULE: &str = "surfmotion::tools::eval::plausibility";

static WARNINGS_IN_SUMMARY: std::sync::atomic::AtomicBool =
    std::sync::atomic::AtomicBool::new(false);

/// Called by a verb whose text summary prints the plausibility report with
/// its warnings (`retarget`, `transfer`, `synth` without `--json`): the
/// same warnings are then not logged on stderr as well (`synth` printed
/// its penetration warning twice, once without the sequence's name). With
/// `--json` they are logged, as the JSON goes to a program.
pub fn warnings_in_summary(text: bool) {
    WARNINGS_IN_SUMMARY.store(text, std::sync::atomic::Ordering::Relaxed);
}

/// Sets up the log: warnings (and `SURFMOTION_LOG`) on stderr, notices
/// as plain lines.
pub fn init() {
    // Warnings (a cache rebuilt, a graph edit that matched nothing, an
    // implausible result) show by default; SURFMOTION_LOG=debug etc. for more.
    // Notices of the jobs layer (target `surfmotion::notice`) are plain
    // lines on stderr, as the verbs printed them before they moved into
    // the library.
    use tracing_subscriber::prelude::*;
    // Reader warnings (target `surfmotion::warning`) are kept in the reports
    // the verbs print (inspect, rig check), so they are not printed again.
    let is_notice = |m: &tracing::Metadata<'_>| m.target() == surfmotion::jobs::batch::NOTICE;
    let is_reader_warning =
        |m: &tracing::Metadata<'_>| m.target() == surfmotion::util::fsutil::WARNING;
    // A result's plausibility warnings, when the verb prints them in its
    // text summary (see [`warnings_in_summary`]).
    let is_summarised = |m: &tracing::Metadata<'_>| {
        WARNINGS_IN_SUMMARY.load(std::sync::atomic::Ordering::Relaxed)
            && m.module_path() == Some(PLAUSIBILITY_MODULE)
    };
    tracing_subscriber::registry()
        .with(
            tracing_subscriber::fmt::layer()
                .without_time()
                .with_target(false)
                .with_ansi(std::io::IsTerminal::is_terminal(&std::io::stderr()))
                .with_writer(|| FlagWriter(Vec::new()))
                .with_filter(
                    tracing_subscriber::EnvFilter::builder()
                        .with_default_directive(tracing::level_filters::LevelFilter::WARN.into())
                        .with_env_var("SURFMOTION_LOG")
                        .from_env_lossy(),
                )
                .with_filter(tracing_subscriber::filter::filter_fn(move |m| {
                    !is_notice(m) && !is_reader_warning(m) && !is_summarised(m)
                })),
        )
        .with(PlainNotices.with_filter(tracing_subscriber::filter::filter_fn(is_notice)))
        .init();
}

/// Prints a notice event's message as one plain line on stderr.
struct PlainNotices;

impl<S: tracing::Subscriber> tracing_subscriber::Layer<S> for PlainNotices {
    fn on_event(&self, e: &tracing::Event<'_>, _: tracing_subscriber::layer::Context<'_, S>) {
        struct Message(String);
        impl tracing::field::Visit for Message {
            fn record_debug(&mut self, f: &tracing::field::Field, v: &dyn std::fmt::Debug) {
                if f.name() == "message" {
                    self.0 = format!("{v:?}");
                }
            }
            fn record_str(&mut self, f: &tracing::field::Field, v: &str) {
                if f.name() == "message" {
                    self.0 = v.to_string();
                }
            }
        }
        let mut m = Message(String::new());
        e.record(&mut m);
        crate::errln!("{}", super::flags::as_flags(&m.0));
    }
}

/// A log line with the library's option names as the CLI's flags
/// ([`super::flags::as_flags`]): buffered, written to stderr when dropped
/// (the log formats each event into one buffer, then drops its writer).
struct FlagWriter(Vec<u8>);

impl std::io::Write for FlagWriter {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.0.extend_from_slice(buf);
        Ok(buf.len())
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

impl Drop for FlagWriter {
    fn drop(&mut self) {
        use std::io::Write as _;
        let line = super::flags::as_flags(&String::from_utf8_lossy(&self.0));
        let _ = std::io::stderr().write_all(line.as_bytes());
    }
}
