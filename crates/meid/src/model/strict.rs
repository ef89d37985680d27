//! Strict, path-tracking deserialisation of model files.
//!
//! serde, left to itself, reads a struct from an array by field order (`slider = [1.2, 5.0]`
//! would be a slider of 1.2 kg at 5 m/s), lets a fixed-size array such as a spring's
//! `nodes = [A, B]` carry extra entries, and words its errors in Rust type names
//! ("expected struct MassSpec", "expected usize"). Every model is therefore read through
//! [`Strict`], a deserializer wrapper that
//!
//! * refuses an array (or a number, a string ...) where a table is expected, naming the
//!   fields the table takes;
//! * refuses an array longer than a fixed-size array field (`nodes`, `offset`, `band_hz` ...);
//! * records the dotted path (`structure.lumped.springs[0].nodes`) of the innermost value
//!   that failed, so every message names the field;
//!
//! and [`message`] rewords serde's messages in the model's terms.

use std::cell::RefCell;
use std::fmt;

use serde::de::{
    self, DeserializeSeed, Deserializer, EnumAccess, Expected, IgnoredAny, MapAccess, SeqAccess,
    Unexpected, VariantAccess, Visitor,
};

/// What the innermost failing value was, recorded as the error travels out.
#[derive(Debug, Default, Clone)]
pub struct Track {
    /// Dotted path of the innermost value whose deserialisation failed (`""`: the whole file).
    pub path: Option<String>,
    /// What that value should have been, when the wrapper knows better than serde's message
    /// (a table's fields, an enum's variants, a fixed array's length).
    pub expected: Option<String>,
    /// The last map key read (to extend the path of its value).
    last_key: Option<String>,
}

/// Deserialises `T` from `de` strictly (module docs); on failure the error and the [`Track`]
/// of where it happened.
pub fn deserialize<'de, T, D>(de: D) -> Result<T, (D::Error, Track)>
where
    T: de::Deserialize<'de>,
    D: Deserializer<'de>,
{
    let track = RefCell::new(Track::default());
    let r = T::deserialize(Strict {
        de,
        path: String::new(),
        track: &track,
    });
    r.map_err(|e| (e, track.into_inner()))
}

/// The message of a failed [`deserialize`]: `path: reworded message` (module docs).
pub fn message(raw: &str, track: &Track) -> String {
    let body = reword(raw.trim(), track.expected.as_deref());
    match track.path.as_deref() {
        Some(p) if !p.is_empty() => format!("{p}: {body}"),
        _ => body,
    }
}

/// Human names for the type names serde puts into "expected ..." messages.
fn humanize_expected(e: &str) -> String {
    let e = e.trim();
    match e {
        "usize" | "u64" | "u32" | "u16" | "u8" => "a whole number >= 0".into(),
        "isize" | "i64" | "i32" | "i16" | "i8" => "a whole number".into(),
        "f64" | "f32" => "a number".into(),
        "a string" | "string" | "a borrowed string" => "a string (in quotes)".into(),
        "a boolean" => "true or false".into(),
        "a sequence" => "an array [ ... ]".into(),
        "a map" => "a table { name = value, ... }".into(),
        _ => e.to_string(),
    }
}

/// Human names for serde's "unexpected" descriptions (`floating point \`10.0\``).
fn humanize_got(g: &str) -> String {
    let g = g.trim();
    if let Some(v) = g.strip_prefix("floating point ") {
        return format!("the number {}", v.trim_matches('`'));
    }
    if let Some(v) = g.strip_prefix("integer ") {
        return format!("the whole number {}", v.trim_matches('`'));
    }
    if let Some(v) = g.strip_prefix("string ") {
        return format!("the string {v}");
    }
    if let Some(v) = g.strip_prefix("boolean ") {
        return format!("the boolean {}", v.trim_matches('`'));
    }
    match g {
        "sequence" => "an array".into(),
        "map" => "a table".into(),
        _ => g.to_string(),
    }
}

fn reword(raw: &str, expected: Option<&str>) -> String {
    // "invalid type: X, expected Y" / "invalid value: X, expected Y"
    for head in ["invalid type: ", "invalid value: "] {
        if let Some(rest) = raw.strip_prefix(head) {
            if let Some((got, exp)) = rest.split_once(", expected ") {
                let exp = expected.map_or_else(|| humanize_expected(exp), str::to_string);
                if got == "unit variant" {
                    // toml::Value's enums: the value's kind is not told.
                    return format!("expected {exp}");
                }
                return format!("expected {exp}; got {}", humanize_got(got));
            }
        }
    }
    // "invalid length 4, expected ..." (also toml's "expected fewer elements in array")
    if let Some(rest) = raw.strip_prefix("invalid length ") {
        if let Some((n, exp)) = rest.split_once(", expected ") {
            let exp = expected.map_or_else(|| humanize_expected(exp), str::to_string);
            return format!("expected {exp}; got {n} values");
        }
    }
    // toml, for an enum given a number or an array.
    if raw.starts_with("wanted string or table") {
        if let Some(e) = expected {
            return format!("expected {e}");
        }
    }
    if raw == "integer number overflowed" || raw == "floating-point number overflowed" {
        return format!("{raw}: the number does not fit a 64-bit integer or float");
    }
    let mut m = raw.to_string();
    if let Some(h) = super::source::did_you_mean(&m) {
        m.push_str(&h);
    }
    m
}

/// What a value is expected to be, in the model's terms.
#[derive(Clone, Copy)]
enum Kind {
    Any,
    /// A table with these fields.
    Struct(&'static [&'static str]),
    /// An array of exactly this many values.
    Tuple(usize),
    /// One of these strings.
    Enum(&'static [&'static str]),
}

impl Kind {
    fn describe(self) -> Option<String> {
        let list = |v: &[&str]| {
            v.iter()
                .map(|s| format!("`{s}`"))
                .collect::<Vec<_>>()
                .join(", ")
        };
        match self {
            Kind::Any => None,
            Kind::Struct(f) => Some(format!(
                "a table {{ name = value, ... }} with the fields {}",
                list(f)
            )),
            Kind::Tuple(n) => Some(format!("an array of exactly {n} values")),
            Kind::Enum(v) => Some(format!("one of {} (a string in quotes)", list(v))),
        }
    }
}

fn record(track: &RefCell<Track>, path: &str, kind: Kind) {
    let mut t = track.borrow_mut();
    if t.path.is_none() {
        t.path = Some(path.to_string());
        t.expected = kind.describe();
    }
}

/// The deserializer wrapper (module docs).
pub struct Strict<'t, D> {
    de: D,
    path: String,
    track: &'t RefCell<Track>,
}

impl<'t, D> Strict<'t, D> {
    fn wrap<V>(&self, v: V, kind: Kind) -> Wrap<'t, V> {
        Wrap {
            v,
            path: self.path.clone(),
            track: self.track,
            kind,
            key: false,
        }
    }
}

macro_rules! forward {
    ($($method:ident),*) => {$(
        fn $method<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value, Self::Error> {
            let w = self.wrap(visitor, Kind::Any);
            let r = self.de.$method(w);
            if r.is_err() { record(self.track, &self.path, Kind::Any); }
            r
        }
    )*};
}

impl<'de, 't, D: Deserializer<'de>> Deserializer<'de> for Strict<'t, D> {
    type Error = D::Error;

    forward!(
        deserialize_any,
        deserialize_bool,
        deserialize_i8,
        deserialize_i16,
        deserialize_i32,
        deserialize_i64,
        deserialize_i128,
        deserialize_u8,
        deserialize_u16,
        deserialize_u32,
        deserialize_u64,
        deserialize_u128,
        deserialize_f32,
        deserialize_f64,
        deserialize_char,
        deserialize_str,
        deserialize_string,
        deserialize_bytes,
        deserialize_byte_buf,
        deserialize_option,
        deserialize_unit,
        deserialize_seq,
        deserialize_map,
        deserialize_identifier,
        deserialize_ignored_any
    );

    fn deserialize_unit_struct<V: Visitor<'de>>(
        self,
        name: &'static str,
        visitor: V,
    ) -> Result<V::Value, Self::Error> {
        let w = self.wrap(visitor, Kind::Any);
        let r = self.de.deserialize_unit_struct(name, w);
        if r.is_err() {
            record(self.track, &self.path, Kind::Any);
        }
        r
    }

    fn deserialize_newtype_struct<V: Visitor<'de>>(
        self,
        name: &'static str,
        visitor: V,
    ) -> Result<V::Value, Self::Error> {
        let w = self.wrap(visitor, Kind::Any);
        let r = self.de.deserialize_newtype_struct(name, w);
        if r.is_err() {
            record(self.track, &self.path, Kind::Any);
        }
        r
    }

    fn deserialize_tuple<V: Visitor<'de>>(
        self,
        len: usize,
        visitor: V,
    ) -> Result<V::Value, Self::Error> {
        let w = self.wrap(visitor, Kind::Tuple(len));
        let r = self.de.deserialize_tuple(len, w);
        if r.is_err() {
            record(self.track, &self.path, Kind::Tuple(len));
        }
        r
    }

    fn deserialize_tuple_struct<V: Visitor<'de>>(
        self,
        name: &'static str,
        len: usize,
        visitor: V,
    ) -> Result<V::Value, Self::Error> {
        let w = self.wrap(visitor, Kind::Tuple(len));
        let r = self.de.deserialize_tuple_struct(name, len, w);
        if r.is_err() {
            record(self.track, &self.path, Kind::Tuple(len));
        }
        r
    }

    fn deserialize_struct<V: Visitor<'de>>(
        self,
        name: &'static str,
        fields: &'static [&'static str],
        visitor: V,
    ) -> Result<V::Value, Self::Error> {
        let w = self.wrap(visitor, Kind::Struct(fields));
        let r = self.de.deserialize_struct(name, fields, w);
        if r.is_err() {
            record(self.track, &self.path, Kind::Struct(fields));
        }
        r
    }

    fn deserialize_enum<V: Visitor<'de>>(
        self,
        name: &'static str,
        variants: &'static [&'static str],
        visitor: V,
    ) -> Result<V::Value, Self::Error> {
        let w = self.wrap(visitor, Kind::Enum(variants));
        let r = self.de.deserialize_enum(name, variants, w);
        if r.is_err() {
            record(self.track, &self.path, Kind::Enum(variants));
        }
        r
    }

    fn is_human_readable(&self) -> bool {
        self.de.is_human_readable()
    }
}

/// The visitor wrapper: refuses non-tables for structs, checks fixed-array lengths, wraps
/// the nested accessors.
struct Wrap<'t, V> {
    v: V,
    path: String,
    track: &'t RefCell<Track>,
    kind: Kind,
    /// This value is a map key: remember it for the path of the value.
    key: bool,
}

impl<V> Wrap<'_, V> {
    fn is_struct(&self) -> bool {
        matches!(self.kind, Kind::Struct(_))
    }
    fn remember(&self, k: &str) {
        if self.key {
            self.track.borrow_mut().last_key = Some(k.to_string());
        }
    }
}

macro_rules! scalar {
    ($($method:ident($t:ty) => $unexp:expr),*) => {$(
        fn $method<E: de::Error>(self, x: $t) -> Result<Self::Value, E> {
            if self.is_struct() {
                #[allow(clippy::redundant_closure_call)]
                return Err(E::invalid_type(($unexp)(&x), &self));
            }
            self.v.$method(x)
        }
    )*};
}

impl<'de, 't, V: Visitor<'de>> Visitor<'de> for Wrap<'t, V> {
    type Value = V::Value;

    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.kind.describe() {
            Some(d) => f.write_str(&d),
            None => self.v.expecting(f),
        }
    }

    scalar!(
        visit_bool(bool) => |x: &bool| Unexpected::Bool(*x),
        visit_i8(i8) => |x: &i8| Unexpected::Signed(i64::from(*x)),
        visit_i16(i16) => |x: &i16| Unexpected::Signed(i64::from(*x)),
        visit_i32(i32) => |x: &i32| Unexpected::Signed(i64::from(*x)),
        visit_i64(i64) => |x: &i64| Unexpected::Signed(*x),
        visit_i128(i128) => |_: &i128| Unexpected::Other("a 128-bit integer"),
        visit_u8(u8) => |x: &u8| Unexpected::Unsigned(u64::from(*x)),
        visit_u16(u16) => |x: &u16| Unexpected::Unsigned(u64::from(*x)),
        visit_u32(u32) => |x: &u32| Unexpected::Unsigned(u64::from(*x)),
        visit_u64(u64) => |x: &u64| Unexpected::Unsigned(*x),
        visit_u128(u128) => |_: &u128| Unexpected::Other("a 128-bit integer"),
        visit_f32(f32) => |x: &f32| Unexpected::Float(f64::from(*x)),
        visit_f64(f64) => |x: &f64| Unexpected::Float(*x),
        visit_char(char) => |x: &char| Unexpected::Char(*x),
        visit_bytes(&[u8]) => |_: &&[u8]| Unexpected::Other("bytes"),
        visit_borrowed_bytes(&'de [u8]) => |_: &&[u8]| Unexpected::Other("bytes"),
        visit_byte_buf(Vec<u8>) => |_: &Vec<u8>| Unexpected::Other("bytes")
    );

    fn visit_str<E: de::Error>(self, x: &str) -> Result<Self::Value, E> {
        if self.is_struct() {
            return Err(E::invalid_type(Unexpected::Str(x), &self));
        }
        self.remember(x);
        self.v.visit_str(x)
    }

    fn visit_borrowed_str<E: de::Error>(self, x: &'de str) -> Result<Self::Value, E> {
        if self.is_struct() {
            return Err(E::invalid_type(Unexpected::Str(x), &self));
        }
        self.remember(x);
        self.v.visit_borrowed_str(x)
    }

    fn visit_string<E: de::Error>(self, x: String) -> Result<Self::Value, E> {
        if self.is_struct() {
            return Err(E::invalid_type(Unexpected::Str(&x), &self));
        }
        self.remember(&x);
        self.v.visit_string(x)
    }

    fn visit_none<E: de::Error>(self) -> Result<Self::Value, E> {
        self.v.visit_none()
    }

    fn visit_unit<E: de::Error>(self) -> Result<Self::Value, E> {
        if self.is_struct() {
            return Err(E::invalid_type(Unexpected::Unit, &self));
        }
        self.v.visit_unit()
    }

    fn visit_some<D2: Deserializer<'de>>(self, d: D2) -> Result<Self::Value, D2::Error> {
        self.v.visit_some(Strict {
            de: d,
            path: self.path,
            track: self.track,
        })
    }

    fn visit_newtype_struct<D2: Deserializer<'de>>(self, d: D2) -> Result<Self::Value, D2::Error> {
        self.v.visit_newtype_struct(Strict {
            de: d,
            path: self.path,
            track: self.track,
        })
    }

    fn visit_seq<A: SeqAccess<'de>>(self, seq: A) -> Result<Self::Value, A::Error> {
        if self.is_struct() {
            return Err(de::Error::invalid_type(Unexpected::Seq, &self));
        }
        let mut s = Seq {
            seq,
            path: self.path.clone(),
            track: self.track,
            index: 0,
        };
        let kind = self.kind;
        let track = self.track;
        let path = self.path.clone();
        let value = self.v.visit_seq(&mut s)?;
        if let Kind::Tuple(n) = kind {
            let mut extra = 0;
            while s.seq.next_element::<IgnoredAny>()?.is_some() {
                extra += 1;
            }
            if extra > 0 {
                record(track, &path, kind);
                return Err(de::Error::invalid_length(n + extra, &KindExpected(kind)));
            }
        }
        Ok(value)
    }

    fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<Self::Value, A::Error> {
        self.v.visit_map(Map {
            map,
            path: self.path,
            track: self.track,
        })
    }

    fn visit_enum<A: EnumAccess<'de>>(self, data: A) -> Result<Self::Value, A::Error> {
        self.v.visit_enum(Enum {
            data,
            path: self.path,
            track: self.track,
        })
    }
}

/// The description of a [`Kind`] as serde's `Expected`.
struct KindExpected(Kind);

impl Expected for KindExpected {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0.describe().unwrap_or_default())
    }
}

/// A seed deserialised through [`Strict`] at `path`.
struct Seed<'t, S> {
    seed: S,
    path: String,
    track: &'t RefCell<Track>,
    key: bool,
}

impl<'de, 't, S: DeserializeSeed<'de>> DeserializeSeed<'de> for Seed<'t, S> {
    type Value = S::Value;

    fn deserialize<D2: Deserializer<'de>>(self, d: D2) -> Result<Self::Value, D2::Error> {
        if self.key {
            self.seed.deserialize(KeyDe {
                de: d,
                track: self.track,
                path: self.path,
            })
        } else {
            self.seed.deserialize(Strict {
                de: d,
                path: self.path,
                track: self.track,
            })
        }
    }
}

/// A map key: remembers the key's text (for the value's path); errors are the map's.
struct KeyDe<'t, D> {
    de: D,
    track: &'t RefCell<Track>,
    path: String,
}

macro_rules! forward_key {
    ($($method:ident),*) => {$(
        fn $method<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value, Self::Error> {
            let w = Wrap { v: visitor, path: self.path.clone(), track: self.track, kind: Kind::Any, key: true };
            let r = self.de.$method(w);
            if r.is_err() { record(self.track, &self.path, Kind::Any); }
            r
        }
    )*};
}

impl<'de, 't, D: Deserializer<'de>> Deserializer<'de> for KeyDe<'t, D> {
    type Error = D::Error;

    forward_key!(
        deserialize_any,
        deserialize_str,
        deserialize_string,
        deserialize_identifier
    );

    serde::forward_to_deserialize_any! {
        bool i8 i16 i32 i64 i128 u8 u16 u32 u64 u128 f32 f64 char bytes byte_buf option unit
        unit_struct newtype_struct seq tuple tuple_struct map struct enum ignored_any
    }
}

struct Seq<'t, A> {
    seq: A,
    path: String,
    track: &'t RefCell<Track>,
    index: usize,
}

impl<'de, 't, A: SeqAccess<'de>> SeqAccess<'de> for Seq<'t, A> {
    type Error = A::Error;

    fn next_element_seed<T: DeserializeSeed<'de>>(
        &mut self,
        seed: T,
    ) -> Result<Option<T::Value>, Self::Error> {
        let path = format!("{}[{}]", self.path, self.index);
        self.index += 1;
        self.seq.next_element_seed(Seed {
            seed,
            path,
            track: self.track,
            key: false,
        })
    }

    fn size_hint(&self) -> Option<usize> {
        self.seq.size_hint()
    }
}

struct Map<'t, A> {
    map: A,
    path: String,
    track: &'t RefCell<Track>,
}

impl<'de, 't, A: MapAccess<'de>> MapAccess<'de> for Map<'t, A> {
    type Error = A::Error;

    fn next_key_seed<K: DeserializeSeed<'de>>(
        &mut self,
        seed: K,
    ) -> Result<Option<K::Value>, Self::Error> {
        self.track.borrow_mut().last_key = None;
        let r = self.map.next_key_seed(Seed {
            seed,
            path: self.path.clone(),
            track: self.track,
            key: true,
        });
        if r.is_err() {
            record(self.track, &self.path, Kind::Any);
        }
        r
    }

    fn next_value_seed<V: DeserializeSeed<'de>>(
        &mut self,
        seed: V,
    ) -> Result<V::Value, Self::Error> {
        let key = self.track.borrow_mut().last_key.take();
        let path = match key {
            Some(k) if self.path.is_empty() => k,
            Some(k) => format!("{}.{k}", self.path),
            None => self.path.clone(),
        };
        let r = self.map.next_value_seed(Seed {
            seed,
            path: path.clone(),
            track: self.track,
            key: false,
        });
        if r.is_err() {
            record(self.track, &path, Kind::Any);
        }
        r
    }

    fn size_hint(&self) -> Option<usize> {
        self.map.size_hint()
    }
}

struct Enum<'t, A> {
    data: A,
    path: String,
    track: &'t RefCell<Track>,
}

impl<'de, 't, A: EnumAccess<'de>> EnumAccess<'de> for Enum<'t, A> {
    type Error = A::Error;
    type Variant = Variant<'t, A::Variant>;

    fn variant_seed<S: DeserializeSeed<'de>>(
        self,
        seed: S,
    ) -> Result<(S::Value, Self::Variant), Self::Error> {
        let (v, variant) = self.data.variant_seed(seed)?;
        Ok((
            v,
            Variant {
                variant,
                path: self.path,
                track: self.track,
            },
        ))
    }
}

struct Variant<'t, A> {
    variant: A,
    path: String,
    track: &'t RefCell<Track>,
}

impl<'de, 't, A: VariantAccess<'de>> VariantAccess<'de> for Variant<'t, A> {
    type Error = A::Error;

    fn unit_variant(self) -> Result<(), Self::Error> {
        self.variant.unit_variant()
    }

    fn newtype_variant_seed<S: DeserializeSeed<'de>>(
        self,
        seed: S,
    ) -> Result<S::Value, Self::Error> {
        self.variant.newtype_variant_seed(Seed {
            seed,
            path: self.path,
            track: self.track,
            key: false,
        })
    }

    fn tuple_variant<V: Visitor<'de>>(
        self,
        len: usize,
        visitor: V,
    ) -> Result<V::Value, Self::Error> {
        self.variant.tuple_variant(
            len,
            Wrap {
                v: visitor,
                path: self.path,
                track: self.track,
                kind: Kind::Tuple(len),
                key: false,
            },
        )
    }

    fn struct_variant<V: Visitor<'de>>(
        self,
        fields: &'static [&'static str],
        visitor: V,
    ) -> Result<V::Value, Self::Error> {
        self.variant.struct_variant(
            fields,
            Wrap {
                v: visitor,
                path: self.path,
                track: self.track,
                kind: Kind::Struct(fields),
                key: false,
            },
        )
    }
}
