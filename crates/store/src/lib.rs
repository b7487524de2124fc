//! The annotation database (SQLite) and its migrations.
#![deny(missing_docs)]
