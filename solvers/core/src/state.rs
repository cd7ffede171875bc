//! The saved state of a run: named sections of flat arrays, as a checkpoint
//! holds them, and their encoding with a checksum.
//!
//! Each solver puts what its next step reads into a [`State`] under names of
//! its own (`dem.position`, `flow.velocity.0`, ...) and takes them back on
//! restore; a missing section, one of another kind or of the wrong length is
//! an error naming it, never a panic. The encoding is little-endian and
//! self-describing:
//!
//! ```text
//! "GRAINFLOW-STATE\0" (16 bytes)  format version (u32)  section count (u64)
//! per section: name length (u32), name (UTF-8), kind (u8), count (u64), data
//! CRC-32 of all the bytes above (u32)  "END\0"
//! ```
//!
//! so that a truncated or corrupted file is refused by its checksum before a
//! single value is read from it.

use crate::Vec3;
use serde::{de::DeserializeOwned, Serialize};
use std::collections::BTreeMap;
use std::fmt;

const MAGIC: &[u8; 16] = b"GRAINFLOW-STATE\0";
const TRAILER: &[u8; 4] = b"END\0";
/// Raised when the encoding changes; a checkpoint of another format version
/// is refused.
pub const FORMAT_VERSION: u32 = 1;

/// Why a state could not be read back.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct StateError(pub String);

impl fmt::Display for StateError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for StateError {}

#[derive(Clone, Debug, PartialEq)]
enum Section {
    F64(Vec<f64>),
    U64(Vec<u64>),
    U32(Vec<u32>),
    U8(Vec<u8>),
}

impl Section {
    fn kind(&self) -> (u8, &'static str) {
        match self {
            Section::F64(_) => (0, "f64"),
            Section::U64(_) => (1, "u64"),
            Section::U32(_) => (2, "u32"),
            Section::U8(_) => (3, "u8"),
        }
    }

    fn len(&self) -> usize {
        match self {
            Section::F64(v) => v.len(),
            Section::U64(v) => v.len(),
            Section::U32(v) => v.len(),
            Section::U8(v) => v.len(),
        }
    }
}

/// Named flat arrays; names are unique and sorted, so that the same state
/// always encodes to the same bytes.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct State {
    sections: BTreeMap<String, Section>,
}

macro_rules! put_and_take {
    ($put:ident, $take:ident, $t:ty, $variant:ident, $what:literal) => {
        #[doc = concat!("Stores `values` (", $what, ") under `name`, replacing what was there.")]
        pub fn $put(&mut self, name: &str, values: &[$t]) {
            self.sections
                .insert(name.to_string(), Section::$variant(values.to_vec()));
        }

        #[doc = concat!("Takes the ", $what, " stored under `name`.")]
        pub fn $take(&mut self, name: &str) -> Result<Vec<$t>, StateError> {
            match self.sections.remove(name) {
                Some(Section::$variant(values)) => Ok(values),
                Some(other) => Err(StateError(format!(
                    "section {name} holds {} values, not {}",
                    other.kind().1,
                    stringify!($t)
                ))),
                None => Err(StateError(format!("section {name} is missing"))),
            }
        }
    };
}

impl State {
    pub fn new() -> Self {
        Self::default()
    }

    put_and_take!(put_f64s, take_f64s, f64, F64, "numbers");
    put_and_take!(put_u64s, take_u64s, u64, U64, "unsigned integers");
    put_and_take!(put_u32s, take_u32s, u32, U32, "32-bit unsigned integers");
    put_and_take!(put_u8s, take_u8s, u8, U8, "bytes");

    pub fn put_f64(&mut self, name: &str, value: f64) {
        self.put_f64s(name, &[value]);
    }

    pub fn take_f64(&mut self, name: &str) -> Result<f64, StateError> {
        let values = self.take_f64s(name)?;
        exactly_one(name, &values)
    }

    pub fn put_u64(&mut self, name: &str, value: u64) {
        self.put_u64s(name, &[value]);
    }

    pub fn take_u64(&mut self, name: &str) -> Result<u64, StateError> {
        let values = self.take_u64s(name)?;
        exactly_one(name, &values)
    }

    pub fn put_usizes(&mut self, name: &str, values: &[usize]) {
        let values: Vec<u64> = values.iter().map(|&v| v as u64).collect();
        self.put_u64s(name, &values);
    }

    pub fn take_usizes(&mut self, name: &str) -> Result<Vec<usize>, StateError> {
        Ok(self
            .take_u64s(name)?
            .into_iter()
            .map(|v| v as usize)
            .collect())
    }

    pub fn put_usize(&mut self, name: &str, value: usize) {
        self.put_u64(name, value as u64);
    }

    pub fn take_usize(&mut self, name: &str) -> Result<usize, StateError> {
        Ok(self.take_u64(name)? as usize)
    }

    /// Stores vectors as x, y, z triples.
    pub fn put_vec3s(&mut self, name: &str, values: &[Vec3]) {
        let flat: Vec<f64> = values.iter().flat_map(|v| [v.x, v.y, v.z]).collect();
        self.put_f64s(name, &flat);
    }

    pub fn take_vec3s(&mut self, name: &str) -> Result<Vec<Vec3>, StateError> {
        let flat = self.take_f64s(name)?;
        if flat.len() % 3 != 0 {
            return Err(StateError(format!(
                "section {name} holds {} numbers, not a whole number of vectors",
                flat.len()
            )));
        }
        Ok(flat
            .chunks_exact(3)
            .map(|v| Vec3::new(v[0], v[1], v[2]))
            .collect())
    }

    /// Takes an array that must hold `len` values (a field of the grid the
    /// restored run has built).
    pub fn take_f64s_of_len(&mut self, name: &str, len: usize) -> Result<Vec<f64>, StateError> {
        let values = self.take_f64s(name)?;
        if values.len() != len {
            return Err(StateError(format!(
                "section {name} holds {} values where {len} are expected",
                values.len()
            )));
        }
        Ok(values)
    }

    /// Stores a small structured value (counters, an analysis' records)
    /// in a compact binary form that keeps every number exactly.
    pub fn put_value<T: Serialize>(&mut self, name: &str, value: &T) {
        let bytes = postcard::to_allocvec(value).expect("an in-memory encoding does not fail");
        self.put_u8s(name, &bytes);
    }

    pub fn take_value<T: DeserializeOwned>(&mut self, name: &str) -> Result<T, StateError> {
        let bytes = self.take_u8s(name)?;
        postcard::from_bytes(&bytes)
            .map_err(|e| StateError(format!("section {name} does not decode: {e}")))
    }

    /// Whether a section of that name is stored.
    pub fn contains(&self, name: &str) -> bool {
        self.sections.contains_key(name)
    }

    /// The names not taken yet.
    pub fn names(&self) -> impl Iterator<Item = &str> {
        self.sections.keys().map(String::as_str)
    }

    /// Moves every section of `other` into this state.
    pub fn absorb(&mut self, other: State) {
        self.sections.extend(other.sections);
    }

    /// The encoded bytes (see the module documentation).
    pub fn encode(&self) -> Vec<u8> {
        let payload: usize = self
            .sections
            .iter()
            .map(|(name, s)| 13 + name.len() + 8 * s.len())
            .sum();
        let mut bytes = Vec::with_capacity(MAGIC.len() + 12 + payload + 8);
        bytes.extend_from_slice(MAGIC);
        bytes.extend_from_slice(&FORMAT_VERSION.to_le_bytes());
        bytes.extend_from_slice(&(self.sections.len() as u64).to_le_bytes());
        for (name, section) in &self.sections {
            bytes.extend_from_slice(&(name.len() as u32).to_le_bytes());
            bytes.extend_from_slice(name.as_bytes());
            bytes.push(section.kind().0);
            bytes.extend_from_slice(&(section.len() as u64).to_le_bytes());
            match section {
                Section::F64(v) => v.iter().for_each(|x| bytes.extend(x.to_le_bytes())),
                Section::U64(v) => v.iter().for_each(|x| bytes.extend(x.to_le_bytes())),
                Section::U32(v) => v.iter().for_each(|x| bytes.extend(x.to_le_bytes())),
                Section::U8(v) => bytes.extend_from_slice(v),
            }
        }
        let checksum = crc32fast::hash(&bytes);
        bytes.extend_from_slice(&checksum.to_le_bytes());
        bytes.extend_from_slice(TRAILER);
        bytes
    }

    /// Reads encoded bytes back; refuses a truncated or corrupted encoding
    /// (its checksum does not match) and one of another format version.
    pub fn decode(bytes: &[u8]) -> Result<State, StateError> {
        let fail = |why: &str| Err(StateError(why.to_string()));
        if bytes.len() < MAGIC.len() + 12 + 8 || &bytes[..MAGIC.len()] != MAGIC {
            return fail("not a grainflow state (it does not start as one)");
        }
        if &bytes[bytes.len() - 4..] != TRAILER {
            return fail("the state is truncated (its end marker is missing)");
        }
        let body = &bytes[..bytes.len() - 8];
        let stored =
            u32::from_le_bytes(bytes[bytes.len() - 8..bytes.len() - 4].try_into().unwrap());
        if crc32fast::hash(body) != stored {
            return fail("the state is corrupted (its checksum does not match its contents)");
        }
        let mut reader = Reader {
            bytes: body,
            at: MAGIC.len(),
        };
        let version = u32::from_le_bytes(reader.take(4)?.try_into().unwrap());
        if version != FORMAT_VERSION {
            return Err(StateError(format!(
                "the state is of format version {version}; this grainflow reads version \
                 {FORMAT_VERSION}"
            )));
        }
        let count = reader.u64()?;
        let mut sections = BTreeMap::new();
        for _ in 0..count {
            let name_len = u32::from_le_bytes(reader.take(4)?.try_into().unwrap()) as usize;
            let name = std::str::from_utf8(reader.take(name_len)?)
                .map_err(|_| StateError("a section name is not UTF-8".into()))?
                .to_string();
            let kind = reader.take(1)?[0];
            let len = reader.u64()? as usize;
            let width = match kind {
                0 | 1 => 8,
                2 => 4,
                3 => 1,
                _ => {
                    return Err(StateError(format!(
                        "section {name} is of unknown kind {kind}"
                    )))
                }
            };
            let data = reader.take(len.checked_mul(width).ok_or_else(|| {
                StateError(format!("section {name} claims an impossible length"))
            })?)?;
            let section = match kind {
                0 => Section::F64(
                    data.chunks_exact(8)
                        .map(|c| f64::from_le_bytes(c.try_into().unwrap()))
                        .collect(),
                ),
                1 => Section::U64(
                    data.chunks_exact(8)
                        .map(|c| u64::from_le_bytes(c.try_into().unwrap()))
                        .collect(),
                ),
                2 => Section::U32(
                    data.chunks_exact(4)
                        .map(|c| u32::from_le_bytes(c.try_into().unwrap()))
                        .collect(),
                ),
                _ => Section::U8(data.to_vec()),
            };
            sections.insert(name, section);
        }
        if reader.at != body.len() {
            return fail("the state has bytes after its last section");
        }
        Ok(State { sections })
    }
}

fn exactly_one<T: Copy>(name: &str, values: &[T]) -> Result<T, StateError> {
    match values {
        [value] => Ok(*value),
        _ => Err(StateError(format!(
            "section {name} holds {} values where one is expected",
            values.len()
        ))),
    }
}

/// Reads the body of an encoding, refusing to read past its end.
struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl<'a> Reader<'a> {
    fn take(&mut self, len: usize) -> Result<&'a [u8], StateError> {
        let end = self
            .at
            .checked_add(len)
            .filter(|&end| end <= self.bytes.len())
            .ok_or_else(|| StateError("the state ends inside a section".into()))?;
        let slice = &self.bytes[self.at..end];
        self.at = end;
        Ok(slice)
    }

    fn u64(&mut self) -> Result<u64, StateError> {
        Ok(u64::from_le_bytes(self.take(8)?.try_into().unwrap()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> State {
        let mut state = State::new();
        state.put_f64s("flow.velocity.0", &[1.0, -0.0, f64::MIN_POSITIVE, 1e300]);
        state.put_vec3s("dem.position", &[Vec3::new(0.1, 0.2, 0.3)]);
        state.put_u64("dem.steps", 12);
        state.put_u32s("dem.partner", &[3, 1, 4]);
        state.put_u8s("dem.state", &[1, 0, 2]);
        state.put_value("loop", &(0.25f64, 7u64, vec![true, false]));
        state
    }

    #[test]
    fn a_state_reads_back_bit_for_bit() {
        let state = sample();
        let mut back = State::decode(&state.encode()).unwrap();
        assert_eq!(back, state);
        let velocity = back.take_f64s("flow.velocity.0").unwrap();
        assert_eq!(velocity[1].to_bits(), (-0.0f64).to_bits());
        assert_eq!(back.take_vec3s("dem.position").unwrap()[0].y, 0.2);
        assert_eq!(back.take_u64("dem.steps").unwrap(), 12);
        let value: (f64, u64, Vec<bool>) = back.take_value("loop").unwrap();
        assert_eq!(value, (0.25, 7, vec![true, false]));
    }

    #[test]
    fn every_truncation_and_every_flipped_byte_is_refused() {
        let bytes = sample().encode();
        for len in 0..bytes.len() {
            assert!(State::decode(&bytes[..len]).is_err(), "truncated to {len}");
        }
        for at in 0..bytes.len() {
            let mut corrupted = bytes.clone();
            corrupted[at] ^= 0x10;
            assert!(State::decode(&corrupted).is_err(), "byte {at} flipped");
        }
    }

    #[test]
    fn a_missing_or_mistyped_section_is_named() {
        let mut state = sample();
        let missing = state.take_f64s("flow.pressure").unwrap_err();
        assert!(missing.0.contains("flow.pressure"), "{missing}");
        let mistyped = state.take_f64s("dem.partner").unwrap_err();
        assert!(mistyped.0.contains("dem.partner") && mistyped.0.contains("u32"));
        let wrong_len = state.take_f64s_of_len("flow.velocity.0", 5).unwrap_err();
        assert!(wrong_len.0.contains("4 values where 5"), "{wrong_len}");
    }
}
