//! Exports to other renderers, so the reference can be checked against them.
//!
//! - [`mitsuba`]: a Mitsuba 3 scene (XML + PLY meshes) with the same camera, lights and
//!   materials (`interreflect export-mitsuba`, `docs/mitsuba.md`).
//! - [`xml`]: the XML element tree the exporter writes, and a strict parser for checking it.

pub mod mitsuba;
pub mod xml;
