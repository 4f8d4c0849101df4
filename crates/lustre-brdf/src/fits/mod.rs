//! Published fits of the MERL materials, loaded by material name: by default from the copies
//! compiled into the library ([`crate::embedded`]), or from any file with `read`.

pub mod abc;
pub mod lafortune;
pub mod sgd;

use crate::error::{Error, Result};
use std::collections::HashMap;
use std::path::Path;

/// A CSV table of one row per material: header names to column index, rows of raw fields.
#[derive(Clone, Debug)]
pub struct FitTable {
    /// The file the table came from.
    pub path: std::path::PathBuf,
    columns: HashMap<String, usize>,
    rows: Vec<Vec<String>>,
    name_column: usize,
}

/// Parses a fit table keyed by a `name` column, wraps it with `wrap`, and checks every material
/// with `check`, so that a bad value is reported when the file is read.
pub(crate) fn parse_checked<T, M>(
    path: &Path,
    bytes: &[u8],
    wrap: impl FnOnce(FitTable) -> T,
    check: impl Fn(&T, &str) -> Result<M>,
) -> Result<T> {
    let table = FitTable::parse(path, bytes, "name")?;
    let names: Vec<String> = table.names().into_iter().map(str::to_string).collect();
    let fits = wrap(table);
    for name in &names {
        check(&fits, name)?;
    }
    Ok(fits)
}

/// Implements `load_default`, `read`, `parse` and `names` for a published-fit table type: a
/// struct with the one field `table: FitTable` and a `material(&self, &str) -> Result<_>` method
/// that validates a row; `$file` is the table's file name and `$bytes` its embedded copy.
macro_rules! fit_table_api {
    ($ty:ident, $file:expr, $bytes:expr) => {
        impl $ty {
            /// The table compiled into the library ([`crate::embedded`]).
            pub fn load_default() -> $crate::error::Result<Self> {
                Self::parse(&$crate::embedded::label($file), $bytes)
            }

            /// Reads a table from `path`.
            pub fn read(path: &std::path::Path) -> $crate::error::Result<Self> {
                let bytes = $crate::error::read_file(path)?;
                Self::parse(path, &bytes)
            }

            /// Parses a table from memory (`path` only names it in errors). Every row must hold
            /// a valid material, so that a bad value is reported when the file is read.
            pub fn parse(path: &std::path::Path, bytes: &[u8]) -> $crate::error::Result<Self> {
                $crate::fits::parse_checked(path, bytes, |table| $ty { table }, Self::material)
            }

            /// Material names in file order.
            pub fn names(&self) -> Vec<&str> {
                self.table.names()
            }
        }
    };
}
pub(crate) use fit_table_api;

impl FitTable {
    /// Reads a comma-separated table whose material names are in column `name_column`.
    pub fn read(path: &Path, name_column: &str) -> Result<Self> {
        let bytes = crate::error::read_file(path)?;
        Self::parse(path, &bytes, name_column)
    }

    /// Parses a table from memory; `path` is used in error messages.
    pub fn parse(path: &Path, bytes: &[u8], name_column: &str) -> Result<Self> {
        let mut rdr = csv::ReaderBuilder::new()
            .has_headers(true)
            .from_reader(bytes);
        let headers = rdr
            .headers()
            .map_err(|e| Error::format(path, format!("unreadable CSV header: {e}")))?
            .clone();
        let columns: HashMap<String, usize> = headers
            .iter()
            .enumerate()
            .map(|(i, h)| (h.trim().to_string(), i))
            .collect();
        let name_col = *columns
            .get(name_column)
            .ok_or_else(|| Error::format(path, format!("no column named {name_column:?}")))?;
        let mut rows = Vec::new();
        for (i, rec) in rdr.records().enumerate() {
            let rec = rec.map_err(|e| Error::format(path, format!("row {}: {e}", i + 2)))?;
            if rec.len() != headers.len() {
                return Err(Error::format(
                    path,
                    format!(
                        "row {} has {} fields, the header has {}",
                        i + 2,
                        rec.len(),
                        headers.len()
                    ),
                ));
            }
            rows.push(rec.iter().map(|s| s.trim().to_string()).collect());
        }
        if rows.is_empty() {
            return Err(Error::format(path, "the table has no rows"));
        }
        Ok(FitTable {
            path: path.to_path_buf(),
            columns,
            rows,
            name_column: name_col,
        })
    }

    /// Material names in file order.
    pub fn names(&self) -> Vec<&str> {
        self.rows
            .iter()
            .map(|r| r[self.name_column].as_str())
            .collect()
    }

    /// The finite number in column `col` of the row for `material`.
    pub fn value(&self, material: &str, col: &str) -> Result<f64> {
        let row = self
            .rows
            .iter()
            .find(|r| r[self.name_column] == material)
            .ok_or_else(|| {
                Error::NotFound(format!(
                    "{}: no material named {material:?}",
                    self.path.display()
                ))
            })?;
        let c = *self
            .columns
            .get(col)
            .ok_or_else(|| Error::format(&self.path, format!("no column named {col:?}")))?;
        let v: f64 = row[c].parse().map_err(|_| {
            Error::format(
                &self.path,
                format!("{material}: column {col} is not a number: {:?}", row[c]),
            )
        })?;
        if !v.is_finite() {
            return Err(Error::format(
                &self.path,
                format!("{material}: column {col} is not finite"),
            ));
        }
        Ok(v)
    }

    /// The three values of columns `{prefix}_r`, `{prefix}_g`, `{prefix}_b`.
    pub fn rgb(&self, material: &str, prefix: &str) -> Result<[f64; 3]> {
        Ok([
            self.value(material, &format!("{prefix}_r"))?,
            self.value(material, &format!("{prefix}_g"))?,
            self.value(material, &format!("{prefix}_b"))?,
        ])
    }
}
