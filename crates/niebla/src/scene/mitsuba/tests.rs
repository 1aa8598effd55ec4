//! Unit tests of the Mitsuba importer.
