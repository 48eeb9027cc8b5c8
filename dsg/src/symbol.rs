//! Spark-DSG node symbols: `(prefix_char << 56) | index`.

use std::fmt;

/// A Spark-DSG `NodeSymbol`: a prefix character in the top 8 bits of a u64 node id
/// and an index in the low 56 bits. `O(3)` is `0x4F00_0000_0000_0003`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct NodeSymbol(pub u64);

impl NodeSymbol {
    /// Mask of the index bits.
    pub const INDEX_MASK: u64 = (1 << 56) - 1;

    /// The symbol for `prefix` and `index`; `index` is truncated to 56 bits.
    pub const fn new(prefix: u8, index: u64) -> Self {
        Self(((prefix as u64) << 56) | (index & Self::INDEX_MASK))
    }

    /// Wraps a raw node id.
    pub const fn from_id(id: u64) -> Self {
        Self(id)
    }

    /// The raw node id.
    pub const fn id(self) -> u64 {
        self.0
    }

    /// The prefix character byte (`b'O'`, `b'a'`, ...).
    pub const fn prefix(self) -> u8 {
        (self.0 >> 56) as u8
    }

    /// The index (low 56 bits).
    pub const fn index(self) -> u64 {
        self.0 & Self::INDEX_MASK
    }
}

impl fmt::Display for NodeSymbol {
    /// `O(3)` when the prefix is a printable ASCII character, else the raw id.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let p = self.prefix();
        if p.is_ascii_graphic() {
            write!(f, "{}({})", p as char, self.index())
        } else {
            write!(f, "{}", self.0)
        }
    }
}

/// Formats a node id as `O(3) [5692549928996306947]` for messages.
pub(crate) fn describe_id(id: u64) -> String {
    let s = NodeSymbol(id);
    if s.prefix().is_ascii_graphic() {
        format!("{s} [{id}]")
    } else {
        id.to_string()
    }
}

/// Whether `name` just spells a node symbol such as `O(0)` or `R(12)`.
pub(crate) fn looks_like_symbol(name: &str) -> bool {
    let b = name.as_bytes();
    b.len() >= 4
        && b[0].is_ascii_graphic()
        && b[1] == b'('
        && b[b.len() - 1] == b')'
        && b[2..b.len() - 1].iter().all(u8::is_ascii_digit)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn symbols_match_spark_dsg_values() {
        assert_eq!(NodeSymbol::new(b'O', 3).id(), 5_692_549_928_996_306_947);
        assert_eq!(NodeSymbol::new(b'a', 0).id(), 6_989_586_621_679_009_792);
        assert_eq!(
            NodeSymbol::from_id(6_989_586_621_679_009_792).to_string(),
            "a(0)"
        );
        assert_eq!(NodeSymbol::new(b'R', 4).index(), 4);
        assert_eq!(NodeSymbol::new(b'R', 4).prefix(), b'R');
        assert_eq!(NodeSymbol(7).to_string(), "7");
    }

    #[test]
    fn symbol_like_names_are_recognised() {
        assert!(looks_like_symbol("O(0)"));
        assert!(looks_like_symbol("R(12)"));
        assert!(!looks_like_symbol("desk"));
        assert!(!looks_like_symbol("O()"));
        assert!(!looks_like_symbol("(1)"));
    }
}
