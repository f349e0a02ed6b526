//! The comma-separated `name=value` pairs of the deformation's
//! measurement switches (`SURFMOTION_REPAIR`, `SURFMOTION_CLOTH`,
//! `SURFMOTION_HOLD`): one reading of a pair and one wording of what is
//! wrong with it.

/// One `name=value` pair of an override text.
pub(crate) struct Pair<'a> {
    /// The name before `=`.
    pub name: &'a str,
    /// The value after `=`.
    pub value: &'a str,
    pair: &'a str,
    names: &'a str,
}

impl Pair<'_> {
    /// Why the pair is refused: `what`, the pair quoted, every name
    /// accepted.
    pub fn bad(&self, what: &str) -> String {
        bad(self.pair, what, self.names)
    }

    /// The value as a switch: `on`/`1`/`true` or `off`/`0`/`false`.
    pub fn switch(&self) -> Result<bool, String> {
        match self.value {
            "on" | "1" | "true" => Ok(true),
            "off" | "0" | "false" => Ok(false),
            _ => Err(self.bad("the value is not on or off")),
        }
    }

    /// The value as a count.
    pub fn count(&self) -> Result<usize, String> {
        self.value
            .parse()
            .map_err(|_| self.bad("the value is not a count"))
    }

    /// The value as a non-negative finite number.
    pub fn number(&self) -> Result<f64, String> {
        match self.value.parse::<f64>() {
            Ok(x) if x.is_finite() && x >= 0.0 => Ok(x),
            _ => Err(self.bad("the value is not a non-negative number")),
        }
    }

    /// The name refused.
    pub fn unknown<T>(&self) -> Result<T, String> {
        Err(self.bad("unknown name"))
    }
}

fn bad(pair: &str, what: &str, names: &str) -> String {
    format!("'{pair}': {what} (accepted: {names})")
}

/// The pairs of `text` (commas between, blanks around ignored), each
/// checked to be `name=value`; `names` lists the accepted names for the
/// errors.
pub(crate) fn pairs<'a>(
    text: &'a str,
    names: &'a str,
) -> impl Iterator<Item = Result<Pair<'a>, String>> {
    text.split(',')
        .map(str::trim)
        .filter(|p| !p.is_empty())
        .map(move |pair| match pair.split_once('=') {
            Some((name, value)) => Ok(Pair {
                name,
                value,
                pair,
                names,
            }),
            None => Err(bad(pair, "not name=value", names)),
        })
}
