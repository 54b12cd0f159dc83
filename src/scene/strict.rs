//! A TOML tree read strictly: where a scene expects a table, a table must stand.
//!
//! serde's derived structs also take a sequence, their fields filled by position, so
//! `cavitation = [90, 240, 0, 1e9]` (or `--set 'cavitation=[...]'`) set the coolant's
//! temperature, pressure, glycol and gap in their declaration order without a word, and
//! `limits = []` was an empty table. [`Strict`] hands the scene's structs tables only; every
//! other value reads as `toml::Value` reads it.

use serde::de::{self, DeserializeSeed, IntoDeserializer, MapAccess, SeqAccess, Visitor};
use toml::Value;

/// A TOML value whose tables and arrays hand their members on as [`Strict`] values, and which
/// refuses anything but a table where a struct is read.
pub struct Strict(pub Value);

/// What serde calls `v` in an "invalid type" message.
fn unexpected(v: &Value) -> de::Unexpected<'_> {
    match v {
        Value::String(s) => de::Unexpected::Str(s),
        Value::Integer(i) => de::Unexpected::Signed(*i),
        Value::Float(f) => de::Unexpected::Float(*f),
        Value::Boolean(b) => de::Unexpected::Bool(*b),
        Value::Datetime(_) => de::Unexpected::Other("a date-time"),
        Value::Array(_) => de::Unexpected::Seq,
        Value::Table(_) => de::Unexpected::Map,
    }
}

impl<'de> de::Deserializer<'de> for Strict {
    type Error = toml::de::Error;

    fn deserialize_any<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value, Self::Error> {
        match self.0 {
            Value::Table(t) => {
                let mut map = Members {
                    iter: t.into_iter(),
                    value: None,
                };
                visitor.visit_map(&mut map)
            }
            Value::Array(a) => visitor.visit_seq(&mut Elements {
                iter: a.into_iter(),
            }),
            other => other.deserialize_any(visitor),
        }
    }

    fn deserialize_struct<V: Visitor<'de>>(
        self,
        _name: &'static str,
        _fields: &'static [&'static str],
        visitor: V,
    ) -> Result<V::Value, Self::Error> {
        match &self.0 {
            Value::Table(_) => self.deserialize_any(visitor),
            other => Err(de::Error::invalid_type(unexpected(other), &"a table")),
        }
    }

    fn deserialize_option<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value, Self::Error> {
        visitor.visit_some(self)
    }

    fn deserialize_newtype_struct<V: Visitor<'de>>(
        self,
        _name: &'static str,
        visitor: V,
    ) -> Result<V::Value, Self::Error> {
        visitor.visit_newtype_struct(self)
    }

    fn deserialize_enum<V: Visitor<'de>>(
        self,
        name: &'static str,
        variants: &'static [&'static str],
        visitor: V,
    ) -> Result<V::Value, Self::Error> {
        self.0.deserialize_enum(name, variants, visitor)
    }

    serde::forward_to_deserialize_any! {
        bool u8 u16 u32 u64 i8 i16 i32 i64 f32 f64 char str string unit seq
        bytes byte_buf map unit_struct tuple_struct tuple ignored_any identifier
    }
}

/// A table's members, each value read as [`Strict`].
struct Members {
    iter: toml::map::IntoIter<String, Value>,
    value: Option<Value>,
}

impl<'de> MapAccess<'de> for Members {
    type Error = toml::de::Error;

    fn next_key_seed<K: DeserializeSeed<'de>>(
        &mut self,
        seed: K,
    ) -> Result<Option<K::Value>, Self::Error> {
        match self.iter.next() {
            Some((k, v)) => {
                self.value = Some(v);
                seed.deserialize(k.into_deserializer()).map(Some)
            }
            None => Ok(None),
        }
    }

    fn next_value_seed<S: DeserializeSeed<'de>>(
        &mut self,
        seed: S,
    ) -> Result<S::Value, Self::Error> {
        let v = self
            .value
            .take()
            .ok_or_else(|| de::Error::custom("a value was asked for before its key"))?;
        seed.deserialize(Strict(v))
    }
}

/// An array's elements, each read as [`Strict`].
struct Elements {
    iter: std::vec::IntoIter<Value>,
}

impl<'de> SeqAccess<'de> for Elements {
    type Error = toml::de::Error;

    fn next_element_seed<S: DeserializeSeed<'de>>(
        &mut self,
        seed: S,
    ) -> Result<Option<S::Value>, Self::Error> {
        self.iter
            .next()
            .map(|v| seed.deserialize(Strict(v)))
            .transpose()
    }

    fn size_hint(&self) -> Option<usize> {
        Some(self.iter.len())
    }
}

#[cfg(test)]
mod tests {
    use super::Strict;

    #[derive(serde::Deserialize, Debug, PartialEq)]
    struct Inner {
        a: f64,
        b: Option<Vec<f64>>,
    }

    #[derive(serde::Deserialize, Debug, PartialEq)]
    struct Outer {
        inner: Inner,
        list: Vec<Inner>,
    }

    fn read(text: &str) -> Result<Outer, String> {
        let v: toml::Value = toml::Value::Table(text.parse().unwrap());
        serde_path_to_error::deserialize(Strict(v))
            .map_err(|e| format!("{}: {}", e.path(), e.inner()))
    }

    /// Regression: a table given as an array was read field by field in order; it is refused,
    /// naming its key, at any depth; tables, arrays of tables and options read as before.
    #[test]
    fn regression_an_array_where_a_table_stands_is_refused() {
        let good = read("list = [{a = 2.0}]\n[inner]\na = 1.0\nb = [1.0, 2.0]\n").unwrap();
        assert_eq!(good.inner.a, 1.0);
        assert_eq!(good.inner.b, Some(vec![1.0, 2.0]));
        assert_eq!(good.list[0].a, 2.0);
        for (text, at) in [
            ("inner = [1.0]\nlist = []\n", "inner"),
            ("inner = []\nlist = []\n", "inner"),
            ("list = [[3.0]]\n[inner]\na = 1.0\n", "list[0]"),
            ("inner = 5\nlist = []\n", "inner"),
        ] {
            let e = read(text).unwrap_err();
            assert!(
                e.starts_with(at) && e.contains("expected a table"),
                "{text}: {e}"
            );
        }
    }
}
