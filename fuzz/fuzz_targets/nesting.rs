//! Differential check of `sequence::nesting_depth`, the pre-scan that keeps deep nesting away
//! from libyaml: it must never report less nesting than serde_yaml (libyaml) actually reaches.
#![no_main]

use libfuzzer_sys::fuzz_target;
use serde::de::{
    self, DeserializeSeed, EnumAccess, IgnoredAny, MapAccess, SeqAccess, VariantAccess, Visitor,
};
use std::cell::Cell;
use std::fmt;

/// Records the deepest collection reached while walking a document.
#[derive(Clone, Copy)]
struct Depth<'a> {
    level: usize,
    max: &'a Cell<usize>,
}

impl Depth<'_> {
    fn inner(self) -> Self {
        self.max.set(self.max.get().max(self.level + 1));
        Depth {
            level: self.level + 1,
            max: self.max,
        }
    }
}

impl<'de> DeserializeSeed<'de> for Depth<'_> {
    type Value = ();
    fn deserialize<D: de::Deserializer<'de>>(self, d: D) -> Result<(), D::Error> {
        d.deserialize_any(self)
    }
}

impl<'de> Visitor<'de> for Depth<'_> {
    type Value = ();
    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("anything")
    }
    fn visit_bool<E>(self, _: bool) -> Result<(), E> {
        Ok(())
    }
    fn visit_i64<E>(self, _: i64) -> Result<(), E> {
        Ok(())
    }
    fn visit_u64<E>(self, _: u64) -> Result<(), E> {
        Ok(())
    }
    fn visit_i128<E>(self, _: i128) -> Result<(), E> {
        Ok(())
    }
    fn visit_u128<E>(self, _: u128) -> Result<(), E> {
        Ok(())
    }
    fn visit_f64<E>(self, _: f64) -> Result<(), E> {
        Ok(())
    }
    fn visit_str<E>(self, _: &str) -> Result<(), E> {
        Ok(())
    }
    fn visit_unit<E>(self) -> Result<(), E> {
        Ok(())
    }
    fn visit_none<E>(self) -> Result<(), E> {
        Ok(())
    }
    fn visit_some<D: de::Deserializer<'de>>(self, d: D) -> Result<(), D::Error> {
        self.deserialize(d)
    }
    fn visit_newtype_struct<D: de::Deserializer<'de>>(self, d: D) -> Result<(), D::Error> {
        self.deserialize(d)
    }
    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<(), A::Error> {
        let inner = self.inner();
        while seq.next_element_seed(inner)?.is_some() {}
        Ok(())
    }
    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<(), A::Error> {
        let inner = self.inner();
        while map.next_key_seed(inner)?.is_some() {
            map.next_value_seed(inner)?;
        }
        Ok(())
    }
    fn visit_enum<A: EnumAccess<'de>>(self, data: A) -> Result<(), A::Error> {
        let (IgnoredAny, variant) = data.variant()?;
        variant.newtype_variant_seed(self)
    }
}

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    // Two ways libyaml's events nest deeper than its scanner, which is what the bound is for
    // (the quadratic time is the scanner's): an alias replays its anchor's node, and after a
    // `?` in a flow sequence the parser swallows the next `]` (or `,` or `:`), so `[?],[?],…`
    // keeps sequences open that the scanner has closed. Both cost memory per event, no more.
    if text.contains(['*', '?']) {
        return;
    }
    let max = Cell::new(0);
    let _ = Depth {
        level: 0,
        max: &max,
    }
    .deserialize(serde_yaml::Deserializer::from_str(text));
    let (bound, line, col) = rayreel::sequence::nesting_depth(text);
    assert!(
        bound >= max.get(),
        "nesting_depth says {bound} (at {line}:{col}) but serde_yaml reached depth {}",
        max.get()
    );
});
