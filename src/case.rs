//! The case file (RON) schema, its defaults and validation.
