//! The machinery behind the parameter declaration in `params/mod.rs`: each parameter's range,
//! wire type and value, and the macro that turns one declaration line per parameter into the
//! struct, its defaults, its validation and the table everything else reads (the wire layout,
//! the scenario schema, the sweep's names, the protocol document's table).

use super::ParamError;

/// What values a parameter accepts (checked by [`Params::validate`](super::Params::validate)).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Range {
    /// Any value of its type (a seed, an enum's defined codes).
    Any,
    /// `lo ..= hi`.
    Within(f32, f32),
    /// 0, which means the text given (e.g. "off"), or `lo ..= hi`.
    ZeroOr(f32, f32, &'static str),
    /// `lo ..=` the value of another parameter.
    UpTo(f32, super::ParamId),
}

/// How a parameter travels on the wire (`Params`, docs/protocol.md) and is written in a
/// scenario.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// IEEE-754 `f32`, 4 bytes.
    F32,
    /// `u8`, 1 byte.
    U8,
    /// `u32`, 4 bytes.
    U32,
    /// An enum as a `u8` code: the names in code order (0, 1, …).
    Code(&'static [&'static str]),
}

impl Kind {
    /// Bytes on the wire.
    pub const fn wire_len(self) -> usize {
        match self {
            Kind::F32 | Kind::U32 => 4,
            Kind::U8 | Kind::Code(_) => 1,
        }
    }
}

/// One parameter's value, as the wire and the scenario reader see it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Value {
    /// An `f32` parameter.
    F32(f32),
    /// A `u8` parameter.
    U8(u8),
    /// A `u32` parameter.
    U32(u32),
    /// An enum parameter's code.
    Code(u8),
}

impl Value {
    /// The value as a number, for range checks.
    pub fn as_f32(self) -> f32 {
        match self {
            Value::F32(v) => v,
            Value::U8(v) | Value::Code(v) => v as f32,
            Value::U32(v) => v as f32,
        }
    }
}

/// A type a parameter can have.
pub trait ParamType: Copy {
    /// Its wire kind.
    const KIND: Kind;
    /// The value.
    fn to_value(self) -> Value;
    /// From a value of the right kind (an enum: a defined code), else `None`.
    fn from_value(v: Value) -> Option<Self>;
}

impl ParamType for f32 {
    const KIND: Kind = Kind::F32;
    fn to_value(self) -> Value {
        Value::F32(self)
    }
    fn from_value(v: Value) -> Option<Self> {
        match v {
            Value::F32(v) => Some(v),
            _ => None,
        }
    }
}

impl ParamType for u8 {
    const KIND: Kind = Kind::U8;
    fn to_value(self) -> Value {
        Value::U8(self)
    }
    fn from_value(v: Value) -> Option<Self> {
        match v {
            Value::U8(v) => Some(v),
            _ => None,
        }
    }
}

impl ParamType for u32 {
    const KIND: Kind = Kind::U32;
    fn to_value(self) -> Value {
        Value::U32(self)
    }
    fn from_value(v: Value) -> Option<Self> {
        match v {
            Value::U32(v) => Some(v),
            _ => None,
        }
    }
}

/// A parameter whose value is one of a few named choices, sent as a `u8` code.
pub trait Choice: Copy + 'static {
    /// Every choice in code order: the code is the index.
    const ALL: &'static [Self];
    /// The names in code order (scenario files, docs).
    const NAMES: &'static [&'static str];
    /// Its code.
    fn code(self) -> u8;
}

/// The choice with code `code`, if any.
pub fn choice_of<C: Choice>(code: u8) -> Option<C> {
    C::ALL.get(usize::from(code)).copied()
}

/// `v` must be finite and within `lo ..= hi`.
pub(super) fn check(name: &'static str, v: f32, lo: f32, hi: f32) -> Result<(), ParamError> {
    use super::ParamProblem;
    let problem = if !v.is_finite() {
        ParamProblem::NonFinite
    } else if v < lo || v > hi {
        ParamProblem::OutOfRange
    } else {
        return Ok(());
    };
    Err(ParamError { name, problem })
}

/// Declares the parameters, one line each: `name: type = default, "unit", range;` under its
/// doc comment. The order is the wire order (the parameter index). Generates [`Params`]
/// (fields with those docs), its `Default`, [`ParamId`] (one variant per parameter, in order)
/// with its name, unit, kind, range and doc, and `Params::get` / `Params::set` by id.
///
/// [`Params`]: super::Params
/// [`ParamId`]: super::ParamId
macro_rules! declare_params {
    (
        $(#[$meta:meta])*
        pub struct Params {
            $(
                $(#[doc = $doc:literal])*
                $name:ident: $ty:ty = $default:expr, $unit:literal, $range:expr;
            )*
        }
    ) => {
        $(#[$meta])*
        #[derive(Clone, Copy, Debug, PartialEq)]
        #[cfg_attr(feature = "defmt", derive(defmt::Format))]
        #[cfg_attr(feature = "serde", derive(serde::Serialize))]
        pub struct Params {
            $( $(#[doc = $doc])* pub $name: $ty, )*
        }

        impl Default for Params {
            /// Each parameter's declared default.
            fn default() -> Self {
                Params { $( $name: $default, )* }
            }
        }

        /// A parameter of [`Params`], by its declaration (and wire) order: `ParamId::x as u8`
        /// is its parameter index on the wire.
        #[allow(non_camel_case_types)]
        #[derive(Clone, Copy, Debug, PartialEq, Eq)]
        #[cfg_attr(feature = "defmt", derive(defmt::Format))]
        #[repr(u8)]
        pub enum ParamId {
            $( $(#[doc = $doc])* $name, )*
        }

        /// Number of parameters.
        pub const PARAM_COUNT: usize = [$( ParamId::$name ),*].len();

        /// The parameters' names in wire order.
        pub const PARAM_NAMES: [&str; PARAM_COUNT] = [$( stringify!($name) ),*];

        impl ParamId {
            /// Every parameter, in wire order.
            pub const ALL: [ParamId; PARAM_COUNT] = [$( ParamId::$name ),*];

            /// Its field name (scenario key, sweep name, error messages).
            pub const fn name(self) -> &'static str {
                match self { $( ParamId::$name => stringify!($name), )* }
            }

            /// Its unit ("" for none).
            pub const fn unit(self) -> &'static str {
                match self { $( ParamId::$name => $unit, )* }
            }

            /// What values it accepts.
            pub const fn range(self) -> Range {
                match self { $( ParamId::$name => $range, )* }
            }

            /// How it travels on the wire.
            pub const fn kind(self) -> Kind {
                match self { $( ParamId::$name => <$ty as ParamType>::KIND, )* }
            }

            /// Its documentation, one line per doc line.
            pub const fn doc(self) -> &'static str {
                match self { $( ParamId::$name => concat!($( $doc, "\n", )* ""), )* }
            }
        }

        impl Params {
            /// The value of parameter `id`.
            pub fn get(&self, id: ParamId) -> Value {
                match id { $( ParamId::$name => ParamType::to_value(self.$name), )* }
            }

            /// Sets parameter `id` to `v`; `false` (and nothing changed) if `v` is not of its
            /// kind or not one of its codes. Ranges are [`Params::validate`]'s.
            pub fn set(&mut self, id: ParamId, v: Value) -> bool {
                match id {
                    $( ParamId::$name => match ParamType::from_value(v) {
                        Some(x) => self.$name = x,
                        None => return false,
                    }, )*
                }
                true
            }
        }
    };
}

/// A range as the docs and the scenario reader write it: `0.02 ..= 1`, `0 (auto) or 1 ..= 64`,
/// `0 ..= v_max`, `any`; π is written π.
impl core::fmt::Display for Range {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        struct Num(f32);
        impl core::fmt::Display for Num {
            fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
                if self.0 == crate::math::PI {
                    f.write_str("π")
                } else {
                    write!(f, "{}", self.0)
                }
            }
        }
        match *self {
            Range::Any => f.write_str("any"),
            Range::Within(lo, hi) => write!(f, "{} ..= {}", Num(lo), Num(hi)),
            Range::ZeroOr(lo, hi, zero) => write!(f, "0 ({zero}) or {} ..= {}", Num(lo), Num(hi)),
            Range::UpTo(lo, other) => write!(f, "{} ..= {}", Num(lo), other.name()),
        }
    }
}

/// A value as a scenario file writes it (an enum by its name).
impl core::fmt::Display for Value {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            Value::F32(v) => write!(f, "{v}"),
            Value::U8(v) | Value::Code(v) => write!(f, "{v}"),
            Value::U32(v) => write!(f, "{v}"),
        }
    }
}
