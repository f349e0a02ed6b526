//! The command line before a verb runs: negative numbers as values, and
//! one line for a value an option refuses or an argument not in UTF-8.

/// The one line for a command line whose argument is not UTF-8: which
/// argument, the option it belongs to, and its bytes (`\xFF` for each one
/// that is not UTF-8). Options and mesh specs (`SEQ.pc2:FRAME`) are text.
pub fn non_utf8_argument(args: Vec<std::ffi::OsString>) -> String {
    let Some(i) = args.iter().position(|a| a.to_str().is_none()) else {
        return "an argument is not valid UTF-8".into();
    };
    let mut shown = String::new();
    for c in args[i].as_encoded_bytes().utf8_chunks() {
        shown.extend(c.valid().chars().flat_map(char::escape_debug));
        for b in c.invalid() {
            shown += &format!("\\x{b:02X}");
        }
    }
    let option = match shown.split_once('=') {
        Some((o, v)) if o.starts_with("--") => Some((o.to_string(), v.to_string())),
        _ => args[..i]
            .last()
            .and_then(|p| p.to_str())
            .filter(|p| i > 1 && p.starts_with('-') && p.len() > 1 && !p.contains('='))
            .map(|p| (p.to_string(), shown.clone())),
    };
    match option {
        Some((o, v)) => format!(
            "{o} '{v}': not valid UTF-8 (argument {i}); this value is read as text: pass it in UTF-8 (rename the file if it is one)"
        ),
        None => format!(
            "argument {i} '{shown}' is not valid UTF-8; this value is read as text: pass it in UTF-8 (rename the file if it is one)"
        ),
    }
}

/// Every option of every verb takes negative numbers as values, so that
/// `--fps -30` reaches the option's parser ("expected a frame rate") instead
/// of being read as a flag `-3` (issue 18, item 17). A numeric option (one
/// value, parsed as a number) takes any value beginning with `-`, so that
/// `--t-skel -inf`, `-nan` or `-.5` reach its check too instead of clap's
/// "unexpected argument '-i'" (clap counts only digits, one dot and one
/// exponent as a negative number).
pub fn allow_negative_numbers(cmd: clap::Command) -> clap::Command {
    cmd.mut_args(|a| {
        if !a.get_action().takes_values() {
            a
        } else if is_numeric_option(&a) {
            a.allow_hyphen_values(true)
        } else {
            a.allow_negative_numbers(true)
        }
    })
    .mut_subcommands(allow_negative_numbers)
}

/// An option (not a positional) that takes one value parsed as a number.
/// Options taking a list stay as they are, so `--frames 1,2 --out x` still
/// ends the list at `--out`.
fn is_numeric_option(a: &clap::Arg) -> bool {
    use std::any::TypeId;
    let one_value = a
        .get_num_args()
        .is_none_or(|n| n.max_values() == 1 && n.min_values() == 1);
    let t = a.get_value_parser().type_id();
    let numeric = [
        TypeId::of::<f64>(),
        TypeId::of::<f32>(),
        TypeId::of::<usize>(),
        TypeId::of::<u64>(),
        TypeId::of::<u32>(),
        TypeId::of::<u16>(),
        TypeId::of::<u8>(),
        TypeId::of::<i64>(),
        TypeId::of::<i32>(),
        TypeId::of::<isize>(),
    ]
    .into_iter()
    .any(|n| t == n);
    a.get_long().is_some() && one_value && numeric && a.get_value_delimiter().is_none()
}

/// One line for a value an option does not take: the option, the value
/// and what it takes (a whole number ≥ 0 for counts and frame indices,
/// the possible values of a choice, or the option's own check).
pub fn bad_value(e: &clap::Error) -> String {
    use clap::error::{ContextKind, ContextValue};
    use std::num::IntErrorKind;
    let text = |k| match e.get(k) {
        Some(ContextValue::String(s)) => Some(s.clone()),
        _ => None,
    };
    // "--frame <FRAME>" → "--frame"; a positional "<DIR>" stays.
    let arg = text(ContextKind::InvalidArg).unwrap_or_else(|| "an argument".into());
    let flag = if arg.starts_with('-') {
        arg.split([' ', '=']).next().unwrap_or(&arg).to_string()
    } else {
        arg.clone()
    };
    let value = text(ContextKind::InvalidValue).unwrap_or_default();
    let source = std::error::Error::source(e);
    let why = if let Some(p) = source.and_then(|s| s.downcast_ref::<std::num::ParseIntError>()) {
        match p.kind() {
            IntErrorKind::Empty => "expected a whole number, got nothing".to_string(),
            IntErrorKind::PosOverflow | IntErrorKind::NegOverflow => {
                "a whole number too large for this option".to_string()
            }
            _ if flag == "--frame" || flag == "--frames" => {
                "expected a frame number: a whole number from 0 (the first frame)".to_string()
            }
            _ => "expected a whole number ≥ 0".to_string(),
        }
    } else if let Some(s) = source {
        s.to_string()
    } else if let Some(ContextValue::Strings(v)) = e.get(ContextKind::ValidValue)
        && !v.is_empty()
    {
        format!("expected one of {}", v.join(", "))
    } else if value.is_empty() {
        return format!("{flag} needs a value");
    } else {
        "not a value this option takes".to_string()
    };
    format!("{flag} '{value}': {why}")
}

/// A command line clap refused (it has printed why): exit 1.
#[derive(Debug, thiserror::Error)]
#[error("bad command line")]
pub struct Usage;
