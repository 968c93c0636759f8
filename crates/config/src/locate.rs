//! Finding where a field sits in a YAML text, for errors found after parsing.
//!
//! serde_yaml reports positions for syntax and type errors but keeps no spans
//! in the values it produces. Cross-field checks (`min < max`, unique IDs, a
//! keyframe inside a joint limit) run on typed values, so their position is
//! recovered here: the text is walked again and a deliberate error is raised
//! at the node named by a [`FieldPath`]; serde_yaml stamps that error with the
//! node's line and column. This only runs when something is wrong (or once
//! per keyframe while loading a motion), so its cost does not matter.

use std::fmt;

use serde::de::{self, DeserializeSeed, IgnoredAny, MapAccess, SeqAccess, Visitor};

/// One step into a YAML document.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum Seg {
    /// A mapping key.
    Key(String),
    /// A sequence index.
    Index(usize),
}

/// A path from the document root to a node, printed like serde_yaml prints
/// its own paths (`buses[0].joints[2].min`).
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct FieldPath(pub(crate) Vec<Seg>);

impl FieldPath {
    /// The root of the document.
    pub fn root() -> Self {
        FieldPath(Vec::new())
    }

    /// This path extended by a key.
    pub fn key(&self, key: &str) -> Self {
        let mut v = self.0.clone();
        v.push(Seg::Key(key.to_owned()));
        FieldPath(v)
    }

    /// This path extended by an index.
    pub fn index(&self, index: usize) -> Self {
        let mut v = self.0.clone();
        v.push(Seg::Index(index));
        FieldPath(v)
    }
}

impl fmt::Display for FieldPath {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, seg) in self.0.iter().enumerate() {
            match seg {
                Seg::Key(k) if i == 0 => write!(f, "{k}")?,
                Seg::Key(k) => write!(f, ".{k}")?,
                Seg::Index(n) => write!(f, "[{n}]")?,
            }
        }
        Ok(())
    }
}

/// Which part of the node at the path to point at.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Part {
    /// The value (for the root: the first node of the document).
    Value,
    /// The key of the last path segment (an unknown joint name, say).
    Key,
}

const PROBE: &str = "\u{0}servobus-probe";

/// 1-based line and column of the node at `path` in `text`, or `None` when
/// the path does not exist (then callers fall back to the parent).
pub(crate) fn locate(text: &str, path: &FieldPath, part: Part) -> Option<(usize, usize)> {
    let probe = Probe {
        path: &path.0,
        depth: 0,
        part,
    };
    let de = serde_yaml::Deserializer::from_str(text);
    match probe.deserialize(de) {
        Ok(()) => None,
        Err(err) => {
            if err.to_string().contains(PROBE) {
                err.location().map(|l| (l.line(), l.column()))
            } else {
                None
            }
        }
    }
}

/// Line and column of the node at `path`, or of its nearest existing
/// ancestor (a missing field is reported where its mapping starts).
pub(crate) fn locate_nearest(text: &str, path: &FieldPath, part: Part) -> (usize, usize) {
    if let Some(at) = locate(text, path, part) {
        return at;
    }
    let mut p = path.clone();
    while !p.0.is_empty() {
        p.0.pop();
        if let Some(at) = locate(text, &p, Part::Value) {
            return at;
        }
    }
    (1, 1)
}

struct Probe<'p> {
    path: &'p [Seg],
    depth: usize,
    part: Part,
}

impl Probe<'_> {
    fn is_target(&self) -> bool {
        self.part == Part::Value && self.depth == self.path.len()
    }
    fn fail<E: de::Error>(&self) -> Result<(), E> {
        if self.is_target() {
            Err(E::custom(PROBE))
        } else {
            Ok(())
        }
    }
}

impl<'de> DeserializeSeed<'de> for Probe<'_> {
    type Value = ();
    fn deserialize<D: de::Deserializer<'de>>(self, d: D) -> Result<(), D::Error> {
        d.deserialize_any(self)
    }
}

impl<'de> Visitor<'de> for Probe<'_> {
    type Value = ();

    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("any YAML node")
    }

    fn visit_bool<E: de::Error>(self, _: bool) -> Result<(), E> {
        self.fail()
    }
    fn visit_i64<E: de::Error>(self, _: i64) -> Result<(), E> {
        self.fail()
    }
    fn visit_u64<E: de::Error>(self, _: u64) -> Result<(), E> {
        self.fail()
    }
    fn visit_f64<E: de::Error>(self, _: f64) -> Result<(), E> {
        self.fail()
    }
    fn visit_str<E: de::Error>(self, _: &str) -> Result<(), E> {
        self.fail()
    }
    fn visit_unit<E: de::Error>(self) -> Result<(), E> {
        self.fail()
    }
    fn visit_none<E: de::Error>(self) -> Result<(), E> {
        self.fail()
    }
    fn visit_some<D: de::Deserializer<'de>>(self, d: D) -> Result<(), D::Error> {
        self.fail::<D::Error>()?;
        d.deserialize_any(self)
    }

    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<(), A::Error> {
        self.fail::<A::Error>()?;
        let want = match self.path.get(self.depth) {
            Some(Seg::Index(n)) => Some(*n),
            _ => None,
        };
        let mut i = 0usize;
        loop {
            let more = if Some(i) == want {
                seq.next_element_seed(Probe {
                    path: self.path,
                    depth: self.depth + 1,
                    part: self.part,
                })?
                .is_some()
            } else {
                seq.next_element::<IgnoredAny>()?.is_some()
            };
            if !more {
                return Ok(());
            }
            i += 1;
        }
    }

    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<(), A::Error> {
        self.fail::<A::Error>()?;
        let want = match self.path.get(self.depth) {
            Some(Seg::Key(k)) => Some(k.as_str()),
            _ => None,
        };
        let key_is_target = self.part == Part::Key && self.depth + 1 == self.path.len();
        while let Some(matched) = map.next_key_seed(KeyProbe {
            want,
            fail_on_match: key_is_target,
        })? {
            if matched {
                map.next_value_seed(Probe {
                    path: self.path,
                    depth: self.depth + 1,
                    part: self.part,
                })?;
            } else {
                map.next_value::<IgnoredAny>()?;
            }
        }
        Ok(())
    }
}

/// Reads a mapping key, says whether it is the wanted one, and raises the
/// probe error on it when the key itself is the target.
struct KeyProbe<'p> {
    want: Option<&'p str>,
    fail_on_match: bool,
}

impl KeyProbe<'_> {
    fn check<E: de::Error>(&self, key: &str) -> Result<bool, E> {
        let matched = self.want == Some(key);
        if matched && self.fail_on_match {
            return Err(E::custom(PROBE));
        }
        Ok(matched)
    }
}

impl<'de> DeserializeSeed<'de> for KeyProbe<'_> {
    type Value = bool;
    fn deserialize<D: de::Deserializer<'de>>(self, d: D) -> Result<bool, D::Error> {
        d.deserialize_any(self)
    }
}

impl<'de> Visitor<'de> for KeyProbe<'_> {
    type Value = bool;

    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("a mapping key")
    }
    fn visit_str<E: de::Error>(self, v: &str) -> Result<bool, E> {
        self.check(v)
    }
    fn visit_bool<E: de::Error>(self, v: bool) -> Result<bool, E> {
        self.check(&v.to_string())
    }
    fn visit_i64<E: de::Error>(self, v: i64) -> Result<bool, E> {
        self.check(&v.to_string())
    }
    fn visit_u64<E: de::Error>(self, v: u64) -> Result<bool, E> {
        self.check(&v.to_string())
    }
    fn visit_f64<E: de::Error>(self, v: f64) -> Result<bool, E> {
        self.check(&v.to_string())
    }
    fn visit_unit<E: de::Error>(self) -> Result<bool, E> {
        Ok(false)
    }
    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<bool, A::Error> {
        while seq.next_element::<IgnoredAny>()?.is_some() {}
        Ok(false)
    }
    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<bool, A::Error> {
        while map.next_entry::<IgnoredAny, IgnoredAny>()?.is_some() {}
        Ok(false)
    }
}
