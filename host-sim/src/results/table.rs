//! One table, written as CSV or as Markdown: a table's columns and cells are declared once,
//! and each format renders them (the bench's `summary.csv` and `summary.md` are one table).

/// A column: its CSV header (several CSV columns when its cells are [`Cell::Fraction`], e.g.
/// `legs_solved,legs`), its Markdown header, and whether it holds numbers (right-aligned in
/// Markdown).
#[derive(Clone, Debug)]
pub struct Column {
    /// The CSV header.
    pub csv: String,
    /// The Markdown header.
    pub md: String,
    /// Right-aligned in Markdown.
    pub numeric: bool,
}

impl Column {
    /// A text column.
    pub fn text(csv: impl Into<String>, md: impl Into<String>) -> Self {
        Self {
            csv: csv.into(),
            md: md.into(),
            numeric: false,
        }
    }

    /// A number column.
    pub fn number(csv: impl Into<String>, md: impl Into<String>) -> Self {
        Self {
            numeric: true,
            ..Self::text(csv, md)
        }
    }
}

/// A cell.
#[derive(Clone, Debug)]
pub enum Cell {
    /// Text as it is.
    Text(String),
    /// Text quoted in CSV (a name holding commas or parentheses).
    Quoted(String),
    /// A number with `csv` decimals in CSV and `md` in Markdown; `-` when absent.
    Number(Option<f64>, usize, usize),
    /// `a` of `b`: two CSV columns, `a/b` in Markdown.
    Fraction(usize, usize),
}

fn number(v: Option<f64>, digits: usize) -> String {
    v.map_or_else(|| "-".into(), |v| format!("{v:.digits$}"))
}

impl Cell {
    fn csv(&self) -> String {
        match self {
            Self::Text(t) => t.clone(),
            Self::Quoted(t) => format!("\"{}\"", t.replace('"', "\"\"")),
            Self::Number(v, d, _) => number(*v, *d),
            Self::Fraction(a, b) => format!("{a},{b}"),
        }
    }

    fn md(&self) -> String {
        match self {
            Self::Text(t) | Self::Quoted(t) => t.replace('|', "\\|"),
            Self::Number(v, _, d) => number(*v, *d),
            Self::Fraction(a, b) => format!("{a}/{b}"),
        }
    }
}

/// A table: columns and rows of cells, one cell per column.
#[derive(Clone, Debug, Default)]
pub struct Table {
    /// The columns.
    pub columns: Vec<Column>,
    /// The rows.
    pub rows: Vec<Vec<Cell>>,
}

impl Table {
    /// The table as CSV: a header line and a line per row.
    pub fn csv(&self) -> String {
        let mut s = self
            .columns
            .iter()
            .map(|c| c.csv.as_str())
            .collect::<Vec<_>>()
            .join(",");
        s.push('\n');
        for r in &self.rows {
            s.push_str(&r.iter().map(Cell::csv).collect::<Vec<_>>().join(","));
            s.push('\n');
        }
        s
    }

    /// The table as Markdown: a header, the alignment line, a line per row.
    pub fn markdown(&self) -> String {
        let line = |cells: Vec<String>| format!("| {} |\n", cells.join(" | "));
        let mut s = line(self.columns.iter().map(|c| c.md.clone()).collect());
        s.push('|');
        for c in &self.columns {
            s.push_str(if c.numeric { "---:|" } else { "---|" });
        }
        s.push('\n');
        for r in &self.rows {
            s.push_str(&line(r.iter().map(Cell::md).collect()));
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_table_two_formats() {
        let t = Table {
            columns: vec![
                Column::text("planner", "planner"),
                Column::number("solved,legs", "legs solved"),
                Column::number("ratio", "ratio"),
            ],
            rows: vec![vec![
                Cell::Quoted("Bi-AM-RRT*(D), tuned".into()),
                Cell::Fraction(2, 3),
                Cell::Number(Some(1.23456), 4, 2),
            ]],
        };
        assert_eq!(
            t.csv(),
            "planner,solved,legs,ratio\n\"Bi-AM-RRT*(D), tuned\",2,3,1.2346\n"
        );
        assert_eq!(
            t.markdown(),
            "| planner | legs solved | ratio |\n|---|---:|---:|\n| Bi-AM-RRT*(D), tuned | 2/3 | 1.23 |\n"
        );
    }
}
