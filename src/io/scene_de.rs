//! A scene's parsed TOML as a serde deserializer that lists every table's `type` key first.
//!
//! A plugin (`Box<dyn MeshSource>`, …) is read by typetag, which buffers the keys it meets
//! before `type`; a field read from that buffer loses its path, so an error inside the plugin
//! named only the plugin's table (`mesh: invalid length 2`). With `type` first, typetag hands
//! the rest of the table straight to the plugin and `serde_path_to_error` follows it down to the
//! field (`mesh.cells`). The scene is read from the one parsed [`toml::Value`]: no text is parsed
//! again.

use serde::de::value::{MapAccessDeserializer, MapDeserializer, SeqDeserializer};
use serde::de::{self, IntoDeserializer, Visitor};
use serde::forward_to_deserialize_any;

/// A borrowed TOML value, read with each table's `type` key first.
#[derive(Clone, Copy, Debug)]
pub struct TypeFirst<'a>(pub &'a toml::Value);

type Error = toml::de::Error;

/// The entries of `t`, `type` first, the others in their order.
fn entries(t: &toml::Table) -> impl Iterator<Item = (&str, TypeFirst<'_>)> {
    let tag = t.get_key_value("type");
    tag.into_iter().chain(t.iter().filter(|(k, _)| k.as_str() != "type")).map(|(k, v)| (k.as_str(), TypeFirst(v)))
}

impl<'de> de::Deserializer<'de> for TypeFirst<'_> {
    type Error = Error;

    fn deserialize_any<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value, Error> {
        match self.0 {
            toml::Value::String(s) => visitor.visit_str(s),
            toml::Value::Integer(i) => visitor.visit_i64(*i),
            toml::Value::Float(x) => visitor.visit_f64(*x),
            toml::Value::Boolean(b) => visitor.visit_bool(*b),
            toml::Value::Datetime(d) => visitor.visit_string(d.to_string()),
            // through their deserializers, which also refuse elements left unread (`[1, 1, 1, 1]`
            // for three coordinates)
            toml::Value::Array(a) => SeqDeserializer::new(a.iter().map(TypeFirst)).deserialize_any(visitor),
            toml::Value::Table(t) => MapDeserializer::new(entries(t)).deserialize_any(visitor),
        }
    }

    /// A key that is present is `Some` (TOML has no null).
    fn deserialize_option<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value, Error> {
        visitor.visit_some(self)
    }

    /// A unit variant is a string (`"kuhn"`), a variant with data a table of one key
    /// (`{ group = "zmin" }`).
    fn deserialize_enum<V: Visitor<'de>>(
        self,
        _name: &'static str,
        _variants: &'static [&'static str],
        visitor: V,
    ) -> Result<V::Value, Error> {
        match self.0 {
            toml::Value::String(s) => visitor.visit_enum(s.as_str().into_deserializer()),
            toml::Value::Table(t) if t.len() == 1 => {
                visitor.visit_enum(MapAccessDeserializer::new(MapDeserializer::new(entries(t))))
            }
            toml::Value::Table(t) => Err(de::Error::invalid_length(t.len(), &"a table of one key, the variant")),
            _ => self.deserialize_any(visitor),
        }
    }

    fn deserialize_newtype_struct<V: Visitor<'de>>(self, _name: &'static str, visitor: V) -> Result<V::Value, Error> {
        visitor.visit_newtype_struct(self)
    }

    forward_to_deserialize_any! {
        bool i8 i16 i32 i64 i128 u8 u16 u32 u64 u128 f32 f64 char str string bytes byte_buf unit unit_struct seq
        tuple tuple_struct map struct identifier ignored_any
    }
}

impl<'de, 'a> IntoDeserializer<'de, Error> for TypeFirst<'a> {
    type Deserializer = TypeFirst<'a>;

    fn into_deserializer(self) -> Self {
        self
    }
}
