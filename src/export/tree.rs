//! A value read with where its text is: the shape the config reader ([`super::cfg`]) and the
//! JSON reader ([`super::jsonedit`]) share, so that an update replaces a value's text and
//! keeps every other byte of a robot's file.

/// A value of kind `K` (a syntax's scalars, maps and lists) with the span of its text.
#[derive(Debug, Clone, PartialEq)]
pub struct Node<K> {
    /// What it is.
    pub kind: K,
    /// Byte offset of its first character.
    pub start: usize,
    /// Byte offset after its last character.
    pub end: usize,
    /// Its line (1-based).
    pub line: usize,
}

/// The kinds of a syntax whose maps (objects) hold named members in file order.
pub trait Members: Sized {
    /// The members, in file order, when this is a map; `None` otherwise.
    fn members(&self) -> Option<&[(String, Node<Self>)]>;
}

impl<K: Members> Node<K> {
    /// The value at `path` below this map.
    pub fn get(&self, path: &[&str]) -> Option<&Node<K>> {
        let Some((first, rest)) = path.split_first() else {
            return Some(self);
        };
        self.kind
            .members()?
            .iter()
            .find(|(k, _)| k == first)
            .and_then(|(_, v)| v.get(rest))
    }
}
