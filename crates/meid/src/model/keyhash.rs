//! A 128-bit hash of a value's typed content through its `serde::Serialize`: every number by
//! its bits, every string by its bytes and length, every sequence and map by its length, every
//! enum variant by its index, every `None` and `Some` by a tag. No text is made: the hash of a
//! structure specification costs one pass over its values.
//!
//! The values are written as tagged bytes into one buffer, which two 64-bit SipHash-1-3 states
//! ([`std::hash::DefaultHasher`], fixed keys, started from different prefixes) read in one
//! pass each to make the 128 bits: two different values give the same hash with a probability
//! of about 2⁻¹²⁸ per pair, far below any other failure of a run.

use std::hash::{DefaultHasher, Hasher};

use serde::ser::{self, Serialize};

/// The running hash: the tagged bytes so far.
pub(crate) struct KeyHasher {
    buf: Vec<u8>,
}

impl KeyHasher {
    pub(crate) fn new() -> Self {
        Self {
            buf: Vec::with_capacity(1024),
        }
    }

    fn bytes(&mut self, tag: u8, bytes: &[u8]) {
        self.buf.push(tag);
        self.buf
            .extend_from_slice(&(bytes.len() as u64).to_le_bytes());
        self.buf.extend_from_slice(bytes);
    }

    fn word(&mut self, tag: u8, v: u64) {
        self.buf.push(tag);
        self.buf.extend_from_slice(&v.to_le_bytes());
    }

    /// Adds `value` (a value that cannot be serialised adds its error's text).
    pub(crate) fn add<T: Serialize + ?Sized>(&mut self, value: &T) {
        if let Err(e) = value.serialize(&mut *self) {
            self.bytes(0xff, e.0.as_bytes());
        }
    }

    /// Adds a string.
    pub(crate) fn add_str(&mut self, s: &str) {
        self.bytes(b's', s.as_bytes());
    }

    /// Adds a number.
    pub(crate) fn add_u64(&mut self, v: u64) {
        self.word(b'u', v);
    }

    /// The 128 bits.
    pub(crate) fn finish(&self) -> u128 {
        let mut a = DefaultHasher::new();
        let mut b = DefaultHasher::new();
        a.write_u8(0xa5);
        b.write_u64(0x9e37_79b9_7f4a_7c15);
        a.write(&self.buf);
        b.write(&self.buf);
        (u128::from(a.finish()) << 64) | u128::from(b.finish())
    }
}

/// Never raised by the hasher itself; serde needs an error type.
#[derive(Debug)]
pub(crate) struct KeyError(String);

impl std::fmt::Display for KeyError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for KeyError {}

impl ser::Error for KeyError {
    fn custom<T: std::fmt::Display>(msg: T) -> Self {
        KeyError(msg.to_string())
    }
}

type R = std::result::Result<(), KeyError>;

impl ser::Serializer for &mut KeyHasher {
    type Ok = ();
    type Error = KeyError;
    type SerializeSeq = Self;
    type SerializeTuple = Self;
    type SerializeTupleStruct = Self;
    type SerializeTupleVariant = Self;
    type SerializeMap = Self;
    type SerializeStruct = Self;
    type SerializeStructVariant = Self;

    fn serialize_bool(self, v: bool) -> R {
        self.word(b'b', u64::from(v));
        Ok(())
    }
    fn serialize_i8(self, v: i8) -> R {
        self.serialize_i64(i64::from(v))
    }
    fn serialize_i16(self, v: i16) -> R {
        self.serialize_i64(i64::from(v))
    }
    fn serialize_i32(self, v: i32) -> R {
        self.serialize_i64(i64::from(v))
    }
    fn serialize_i64(self, v: i64) -> R {
        self.word(b'i', v as u64);
        Ok(())
    }
    fn serialize_u8(self, v: u8) -> R {
        self.serialize_u64(u64::from(v))
    }
    fn serialize_u16(self, v: u16) -> R {
        self.serialize_u64(u64::from(v))
    }
    fn serialize_u32(self, v: u32) -> R {
        self.serialize_u64(u64::from(v))
    }
    fn serialize_u64(self, v: u64) -> R {
        self.word(b'u', v);
        Ok(())
    }
    fn serialize_f32(self, v: f32) -> R {
        self.serialize_f64(f64::from(v))
    }
    fn serialize_f64(self, v: f64) -> R {
        self.word(b'f', v.to_bits());
        Ok(())
    }
    fn serialize_char(self, v: char) -> R {
        self.word(b'c', u64::from(u32::from(v)));
        Ok(())
    }
    fn serialize_str(self, v: &str) -> R {
        self.bytes(b's', v.as_bytes());
        Ok(())
    }
    fn serialize_bytes(self, v: &[u8]) -> R {
        self.bytes(b'y', v);
        Ok(())
    }
    fn serialize_none(self) -> R {
        self.word(b'n', 0);
        Ok(())
    }
    fn serialize_some<T: Serialize + ?Sized>(self, value: &T) -> R {
        self.word(b'S', 0);
        value.serialize(self)
    }
    fn serialize_unit(self) -> R {
        self.word(b'(', 0);
        Ok(())
    }
    fn serialize_unit_struct(self, _name: &'static str) -> R {
        self.serialize_unit()
    }
    fn serialize_unit_variant(self, _name: &'static str, index: u32, _v: &'static str) -> R {
        self.word(b'v', u64::from(index));
        Ok(())
    }
    fn serialize_newtype_struct<T: Serialize + ?Sized>(self, _n: &'static str, value: &T) -> R {
        value.serialize(self)
    }
    fn serialize_newtype_variant<T: Serialize + ?Sized>(
        self,
        _name: &'static str,
        index: u32,
        _variant: &'static str,
        value: &T,
    ) -> R {
        self.word(b'v', u64::from(index));
        value.serialize(self)
    }
    fn serialize_seq(self, len: Option<usize>) -> std::result::Result<Self, KeyError> {
        self.word(b'[', len.map_or(u64::MAX, |n| n as u64));
        Ok(self)
    }
    fn serialize_tuple(self, len: usize) -> std::result::Result<Self, KeyError> {
        self.serialize_seq(Some(len))
    }
    fn serialize_tuple_struct(
        self,
        _name: &'static str,
        len: usize,
    ) -> std::result::Result<Self, KeyError> {
        self.serialize_seq(Some(len))
    }
    fn serialize_tuple_variant(
        self,
        _name: &'static str,
        index: u32,
        _variant: &'static str,
        len: usize,
    ) -> std::result::Result<Self, KeyError> {
        self.word(b'v', u64::from(index));
        self.serialize_seq(Some(len))
    }
    fn serialize_map(self, len: Option<usize>) -> std::result::Result<Self, KeyError> {
        self.word(b'{', len.map_or(u64::MAX, |n| n as u64));
        Ok(self)
    }
    fn serialize_struct(
        self,
        _name: &'static str,
        _len: usize,
    ) -> std::result::Result<Self, KeyError> {
        // Fields are added with their names: a field skipped when empty cannot shift the
        // values after it into another field's place.
        self.word(b'{', 0);
        Ok(self)
    }
    fn serialize_struct_variant(
        self,
        _name: &'static str,
        index: u32,
        _variant: &'static str,
        _len: usize,
    ) -> std::result::Result<Self, KeyError> {
        self.word(b'v', u64::from(index));
        self.serialize_struct("", 0)
    }
}

impl ser::SerializeSeq for &mut KeyHasher {
    type Ok = ();
    type Error = KeyError;
    fn serialize_element<T: Serialize + ?Sized>(&mut self, value: &T) -> R {
        value.serialize(&mut **self)
    }
    fn end(self) -> R {
        self.word(b']', 0);
        Ok(())
    }
}

impl ser::SerializeTuple for &mut KeyHasher {
    type Ok = ();
    type Error = KeyError;
    fn serialize_element<T: Serialize + ?Sized>(&mut self, value: &T) -> R {
        value.serialize(&mut **self)
    }
    fn end(self) -> R {
        self.word(b']', 0);
        Ok(())
    }
}

impl ser::SerializeTupleStruct for &mut KeyHasher {
    type Ok = ();
    type Error = KeyError;
    fn serialize_field<T: Serialize + ?Sized>(&mut self, value: &T) -> R {
        value.serialize(&mut **self)
    }
    fn end(self) -> R {
        self.word(b']', 0);
        Ok(())
    }
}

impl ser::SerializeTupleVariant for &mut KeyHasher {
    type Ok = ();
    type Error = KeyError;
    fn serialize_field<T: Serialize + ?Sized>(&mut self, value: &T) -> R {
        value.serialize(&mut **self)
    }
    fn end(self) -> R {
        self.word(b']', 0);
        Ok(())
    }
}

impl ser::SerializeMap for &mut KeyHasher {
    type Ok = ();
    type Error = KeyError;
    fn serialize_key<T: Serialize + ?Sized>(&mut self, key: &T) -> R {
        key.serialize(&mut **self)
    }
    fn serialize_value<T: Serialize + ?Sized>(&mut self, value: &T) -> R {
        value.serialize(&mut **self)
    }
    fn end(self) -> R {
        self.word(b'}', 0);
        Ok(())
    }
}

impl ser::SerializeStruct for &mut KeyHasher {
    type Ok = ();
    type Error = KeyError;
    fn serialize_field<T: Serialize + ?Sized>(&mut self, key: &'static str, value: &T) -> R {
        self.bytes(b'k', key.as_bytes());
        value.serialize(&mut **self)
    }
    fn end(self) -> R {
        self.word(b'}', 0);
        Ok(())
    }
}

impl ser::SerializeStructVariant for &mut KeyHasher {
    type Ok = ();
    type Error = KeyError;
    fn serialize_field<T: Serialize + ?Sized>(&mut self, key: &'static str, value: &T) -> R {
        self.bytes(b'k', key.as_bytes());
        value.serialize(&mut **self)
    }
    fn end(self) -> R {
        self.word(b'}', 0);
        Ok(())
    }
}
