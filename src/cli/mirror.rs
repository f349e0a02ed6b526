//! [`mirror!`]: the `From` conversions, both ways, between a clap value
//! enum of the command line and the library enum it mirrors (the library
//! does not depend on clap). One definition for every mirror.

/// `mirror!(Arg, Lib, A, B, ...)`: `From<Lib> for Arg` and `From<Arg> for
/// Lib`, variant `A` to variant `A` and so on; every variant of both
/// enums is listed, so a variant added to one side fails to compile.
macro_rules! mirror {
    ($arg:ident, $lib:ty, $($v:ident),+ $(,)?) => {
        impl From<$lib> for $arg {
            fn from(v: $lib) -> Self {
                match v {
                    $(<$lib>::$v => $arg::$v,)+
                }
            }
        }
        impl From<$arg> for $lib {
            fn from(v: $arg) -> Self {
                match v {
                    $($arg::$v => <$lib>::$v,)+
                }
            }
        }
    };
}

pub(crate) use mirror;
