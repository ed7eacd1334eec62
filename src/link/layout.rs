//! Named fields of the messages' layouts, in smoltcp's `wire/` shape: each message's file has a
//! `field` module with one [`Field`] per row of its table in `docs/protocol.md` — the row an
//! error names, the byte offset, the wire type and the name — and parse, emit and the error
//! reports use those names, not bare numbers. `tests/protocol_doc.rs` checks every `field`
//! module (and the `Params` declaration) against the document's tables.

use super::{Error, Problem};

/// One row of a message's layout table.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Field {
    /// The row: what a refusal ([`Error::Field`], a `Reply`'s `field`) names.
    pub row: u8,
    /// Byte offset in the payload (for a `Contacts` entry's fields, in the entry), before
    /// [`Field::plus`].
    pub offset: usize,
    /// What follows the offset in the document when it is not fixed (`" + s"`: after a shape).
    pub plus: &'static str,
    /// The wire type as the document writes it (`u8`, `f32`, `shape`, `n × u8`, …).
    pub ty: &'static str,
    /// The field's name.
    pub name: &'static str,
}

impl Field {
    /// Row `row` at `offset`, of type `ty`, called `name`.
    pub const fn new(row: u8, offset: usize, ty: &'static str, name: &'static str) -> Field {
        Field {
            row,
            offset,
            plus: "",
            ty,
            name,
        }
    }

    /// The same field at an offset that depends on what precedes it (`" + s"`).
    pub const fn plus(self, plus: &'static str) -> Field {
        Field { plus, ..self }
    }

    /// The refusal of this field for `problem`.
    pub const fn error(self, problem: Problem) -> Error {
        Error::field(self.row, problem)
    }
}
