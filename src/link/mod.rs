//! The serial link's wire format (placeholder; see docs/protocol.md when written).
