//! Feature values and the string interner.

use rustc_hash::FxHashMap;

/// An owned feature value, as given to [`crate::SceneGraph::set_feature`].
#[derive(Clone, Debug, PartialEq)]
pub enum FeatureValue {
    /// A string (interned by the graph).
    Str(String),
    /// A signed integer.
    Int(i64),
    /// A float (NaN is refused).
    Float(f64),
    /// A boolean.
    Bool(bool),
}

impl FeatureValue {
    /// A borrowed view of this value.
    pub fn as_ref(&self) -> FeatureRef<'_> {
        match self {
            FeatureValue::Str(s) => FeatureRef::Str(s),
            FeatureValue::Int(v) => FeatureRef::Int(*v),
            FeatureValue::Float(v) => FeatureRef::Float(*v),
            FeatureValue::Bool(v) => FeatureRef::Bool(*v),
        }
    }
}

impl From<&str> for FeatureValue {
    fn from(s: &str) -> Self {
        FeatureValue::Str(s.to_owned())
    }
}
impl From<i64> for FeatureValue {
    fn from(v: i64) -> Self {
        FeatureValue::Int(v)
    }
}
impl From<f64> for FeatureValue {
    fn from(v: f64) -> Self {
        FeatureValue::Float(v)
    }
}
impl From<bool> for FeatureValue {
    fn from(v: bool) -> Self {
        FeatureValue::Bool(v)
    }
}

/// A feature value borrowed from a live graph or a snapshot.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FeatureRef<'a> {
    /// A string.
    Str(&'a str),
    /// A signed integer.
    Int(i64),
    /// A float.
    Float(f64),
    /// A boolean.
    Bool(bool),
}

impl FeatureRef<'_> {
    /// An owned copy.
    pub fn to_owned(&self) -> FeatureValue {
        match *self {
            FeatureRef::Str(s) => FeatureValue::Str(s.to_owned()),
            FeatureRef::Int(v) => FeatureValue::Int(v),
            FeatureRef::Float(v) => FeatureValue::Float(v),
            FeatureRef::Bool(v) => FeatureValue::Bool(v),
        }
    }
}

/// Archived kind tag of a string feature.
pub(crate) const FEATURE_STR: u8 = 0;
/// Archived kind tag of an integer feature.
pub(crate) const FEATURE_INT: u8 = 1;
/// Archived kind tag of a float feature.
pub(crate) const FEATURE_FLOAT: u8 = 2;
/// Archived kind tag of a boolean feature.
pub(crate) const FEATURE_BOOL: u8 = 3;

/// An interned string's handle, valid within one [`Interner`].
pub(crate) type Sym = u32;

/// Interns strings (feature keys, string values, labels, edge descriptions).
/// Strings are never removed: a scene's vocabulary is small and stable.
#[derive(Default, Clone, Debug)]
pub(crate) struct Interner {
    map: FxHashMap<Box<str>, Sym>,
    strings: Vec<Box<str>>,
}

impl Interner {
    /// The handle of `s`, interning it if new.
    pub(crate) fn intern(&mut self, s: &str) -> Sym {
        if let Some(&sym) = self.map.get(s) {
            return sym;
        }
        let sym = self.strings.len() as Sym;
        self.strings.push(s.into());
        self.map.insert(s.into(), sym);
        sym
    }

    /// The handle of `s` if it was ever interned.
    pub(crate) fn get(&self, s: &str) -> Option<Sym> {
        self.map.get(s).copied()
    }

    /// The string of a handle.
    pub(crate) fn resolve(&self, sym: Sym) -> &str {
        &self.strings[sym as usize]
    }
}

/// A feature value as the live graph stores it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum StoredValue {
    Str(Sym),
    Int(i64),
    Float(f64),
    Bool(bool),
}
