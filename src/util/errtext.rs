//! Error texts for one line of output: an error and its causes joined
//! with each part said once ([`one_line`]), without the OS's error
//! numbers ([`without_os_error_numbers`]). For any front end that prints
//! a library error on one line (the command line, a log).

/// An error and its causes on one line, without the OS's error numbers.
/// A cause already said is left out, and a cause that begins with what its
/// context said continues it rather than repeating it (`eval --result
/// FOLDER` printed "FOLDER: FOLDER: no .obj files in the folder").
pub fn one_line(e: &(dyn std::error::Error + 'static)) -> String {
    let mut s = e.to_string();
    let mut cause = e.source();
    while let Some(c) = cause {
        cause = c.source();
        let c = c.to_string();
        if s.contains(&c) {
            continue;
        }
        // The longest tail of `s` (whole, or after a ": ") that `c` begins with.
        let tails = std::iter::once(0).chain(s.match_indices(": ").map(|(i, _)| i + 2));
        match tails.into_iter().find(|&i| c.starts_with(&s[i..])) {
            Some(i) => {
                s.truncate(i);
                s.push_str(&c);
            }
            None => {
                s.push_str(": ");
                s.push_str(&c);
            }
        }
    }
    without_os_error_numbers(&s.replace('\n', " "))
}

/// `s` without the OS's " (os error N)" suffixes: "x.bvh: No such file or
/// directory (os error 2)" says what is wrong without them.
pub fn without_os_error_numbers(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    let mut rest = s;
    while let Some(i) = rest.find(" (os error ") {
        let tail = &rest[i + " (os error ".len()..];
        let digits = tail.bytes().take_while(u8::is_ascii_digit).count();
        if digits > 0 && tail[digits..].starts_with(')') {
            out.push_str(&rest[..i]);
            rest = &tail[digits + 1..];
        } else {
            out.push_str(&rest[..i + 1]);
            rest = &rest[i + 1..];
        }
    }
    out.push_str(rest);
    out
}

#[cfg(test)]
mod tests {
    /// The OS's error numbers are not printed.
    #[test]
    fn os_error_numbers_are_left_out() {
        assert_eq!(
            super::without_os_error_numbers(
                "a.bvh: No such file or directory (os error 2); b: Permission denied (os error 13)"
            ),
            "a.bvh: No such file or directory; b: Permission denied"
        );
        assert_eq!(
            super::without_os_error_numbers("x (os error y) (os error 7"),
            "x (os error y) (os error 7"
        );
    }

    /// Regression (session 6 review): `eval --result FOLDER` printed the
    /// folder twice; a cause that begins with its context continues it.
    #[test]
    fn one_line_says_each_part_once() {
        #[derive(Debug, thiserror::Error)]
        #[error("{0}")]
        struct E(String, #[source] Option<Box<E>>);
        let e = |s: &str, c: Option<E>| E(s.into(), c.map(Box::new));
        let chain = |x: E| super::one_line(&x);
        let inner = || e("out: no .obj files in the folder", None);
        assert_eq!(
            chain(e("out", Some(inner()))),
            "out: no .obj files in the folder"
        );
        assert_eq!(
            chain(e("eval: out", Some(inner()))),
            "eval: out: no .obj files in the folder"
        );
        assert_eq!(
            chain(e("loading", Some(inner()))),
            "loading: out: no .obj files in the folder"
        );
        assert_eq!(chain(e("a: b", Some(e("b", None)))), "a: b");
    }
}
