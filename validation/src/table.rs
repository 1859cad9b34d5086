//! Report tables declared column by column: one line per column, a header and a function
//! from a named row to its cell, so a header and its cell can never drift apart.
//!
//! ```
//! use validation::table::Columns;
//! struct Row { n: usize, error: f64 }
//! let rows = [Row { n: 1000, error: 0.031 }, Row { n: 2000, error: 0.024 }];
//! let t = Columns::new()
//!     .column("N", |r: &Row| r.n.to_string())
//!     .column("error", |r: &Row| format!("{:.1} %", 100.0 * r.error))
//!     .table("Error against N", &rows);
//! assert_eq!(t.header, ["N", "error"]);
//! assert_eq!(t.rows[1], ["2000", "2.4 %"]);
//! ```

use crate::outcome::Table;

/// A cell function: formats one column of a row.
type Cell<'a, R> = Box<dyn Fn(&R) -> String + 'a>;

/// The columns of a table over rows of type `R`, in order.
pub struct Columns<'a, R> {
    columns: Vec<(String, Cell<'a, R>)>,
}

impl<R> Default for Columns<'_, R> {
    fn default() -> Self {
        Self { columns: Vec::new() }
    }
}

impl<'a, R> Columns<'a, R> {
    /// No column yet.
    pub fn new() -> Self {
        Self::default()
    }

    /// Appends a column: its header and how a row fills it.
    pub fn column(mut self, header: impl Into<String>, cell: impl Fn(&R) -> String + 'a) -> Self {
        self.columns.push((header.into(), Box::new(cell)));
        self
    }

    /// Appends one column per item of `items` (e.g. one per model), each headed by `header(item)`
    /// and filled by `cell(item, row)`.
    pub fn columns_for<I: Clone + 'a>(
        mut self,
        items: impl IntoIterator<Item = I>,
        header: impl Fn(&I) -> String,
        cell: impl Fn(&I, &R) -> String + Clone + 'a,
    ) -> Self {
        for item in items {
            let h = header(&item);
            let c = cell.clone();
            self.columns.push((h, Box::new(move |r: &R| c(&item, r))));
        }
        self
    }

    /// The header row.
    pub fn header(&self) -> Vec<String> {
        self.columns.iter().map(|(h, _)| h.clone()).collect()
    }

    /// The formatted cells of one row.
    pub fn row(&self, r: &R) -> Vec<String> {
        self.columns.iter().map(|(_, cell)| cell(r)).collect()
    }

    /// A table titled `title` with one line per row of `rows`.
    pub fn table<'r>(&self, title: impl Into<String>, rows: impl IntoIterator<Item = &'r R>) -> Table
    where
        R: 'r,
    {
        Table {
            title: title.into(),
            header: self.header(),
            rows: rows.into_iter().map(|r| self.row(r)).collect(),
        }
    }
}
