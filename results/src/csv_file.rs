//! CSV text, written and read in one place over the `csv` crate: the harness's `results.csv` and
//! the dashboard's `?format=csv` exports. RFC 4180: a field holding a comma, a quote, a carriage
//! return or a line feed is quoted (quotes doubled), records end with `\n`, the header first.
//!
//! An export a person opens in a spreadsheet guards formula cells ([`Formulas::Guard`]): text
//! starting with `=`, `+`, `-`, `@`, a tab or a carriage return gets a leading `'`, as OWASP
//! advises, so `=HYPERLINK(...)` in a name is shown, not run; a number (`-0.05`, `+1e3`) is left
//! as it is. A result file keeps its text as written ([`Formulas::Keep`]).
//!
//! Not for: what the rows hold (`results.csv`'s columns are [`crate::CSV_COLUMNS`], filled by the
//! harness; each export builds its own rows).

use std::borrow::Cow;

/// What happens to a cell a spreadsheet would run as a formula.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Formulas {
    /// Written as it is (result files: the value is data, read back by programs).
    Keep,
    /// Prefixed with `'` (exports opened in spreadsheets).
    Guard,
}

/// Errors reading CSV text.
#[derive(Debug, thiserror::Error)]
pub enum CsvError {
    #[error("CSV line {line}: {message}")]
    Malformed { line: u64, message: String },
    #[error("CSV header is {found:?}; expected {expected:?}")]
    Header {
        found: Vec<String>,
        expected: Vec<String>,
    },
}

/// `s` as a spreadsheet cell: with a leading `'` when it would be run as a formula.
pub fn guard_formula(s: &str) -> Cow<'_, str> {
    let formula = s.starts_with(['=', '+', '-', '@', '\t', '\r']) && s.parse::<f64>().is_err();
    if formula {
        Cow::Owned(format!("'{s}"))
    } else {
        Cow::Borrowed(s)
    }
}

/// The header and rows as CSV text.
pub fn write<R, C>(header: &[&str], rows: R, formulas: Formulas) -> Vec<u8>
where
    R: IntoIterator,
    R::Item: IntoIterator<Item = C>,
    C: AsRef<str>,
{
    let mut w = csv::WriterBuilder::new()
        .terminator(csv::Terminator::Any(b'\n'))
        .flexible(true)
        .from_writer(Vec::new());
    let cell = |s: &str| -> String {
        match formulas {
            Formulas::Keep => s.to_string(),
            Formulas::Guard => guard_formula(s).into_owned(),
        }
    };
    // Writing to a `Vec` cannot fail.
    w.write_record(header.iter().map(|h| cell(h)))
        .expect("CSV into memory");
    for row in rows {
        let fields: Vec<String> = row.into_iter().map(|f| cell(f.as_ref())).collect();
        w.write_record(&fields).expect("CSV into memory");
    }
    w.into_inner().expect("CSV into memory")
}

/// CSV text read back: its header and rows of fields.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Table {
    pub header: Vec<String>,
    pub rows: Vec<Vec<String>>,
}

/// Reads CSV text; every row must have as many fields as the header. `expected`, when given, is
/// the header the text must start with.
pub fn read(bytes: &[u8], expected: Option<&[&str]>) -> Result<Table, CsvError> {
    let mut r = csv::ReaderBuilder::new()
        .has_headers(true)
        .from_reader(bytes);
    let malformed = |e: csv::Error| {
        let line = e.position().map_or(1, |p| p.line());
        let message = match e.kind() {
            csv::ErrorKind::UnequalLengths {
                expected_len, len, ..
            } => format!("{len} fields where the header has {expected_len}"),
            csv::ErrorKind::Utf8 { err, .. } => format!("not UTF-8: {err}"),
            _ => e.to_string(),
        };
        CsvError::Malformed { line, message }
    };
    let header: Vec<String> = r
        .headers()
        .map_err(malformed)?
        .iter()
        .map(str::to_string)
        .collect();
    if let Some(exp) = expected {
        if header != exp {
            return Err(CsvError::Header {
                found: header,
                expected: exp.iter().map(|s| s.to_string()).collect(),
            });
        }
    }
    let mut rows = Vec::new();
    for rec in r.records() {
        let rec = rec.map_err(malformed)?;
        rows.push(rec.iter().map(str::to_string).collect());
    }
    Ok(Table { header, rows })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn text(header: &[&str], rows: &[Vec<&str>], f: Formulas) -> String {
        String::from_utf8(write(header, rows, f)).unwrap()
    }

    #[test]
    fn quotes_what_needs_it_and_nothing_else() {
        assert_eq!(
            text(
                &["a", "b"],
                &[vec!["upscale[scale=0.5,x=1]", "say \"hi\""]],
                Formulas::Keep
            ),
            "a,b\n\"upscale[scale=0.5,x=1]\",\"say \"\"hi\"\"\"\n"
        );
        assert_eq!(
            text(
                &["a", "b"],
                &[vec!["two\nlines", "cr\rhere"]],
                Formulas::Keep
            ),
            "a,b\n\"two\nlines\",\"cr\rhere\"\n"
        );
        // Plain names, numbers, empty cells and spaces are written bare.
        assert_eq!(
            text(
                &["a", "b", "c", "d"],
                &[vec!["native", "-0.05", "", "a b"]],
                Formulas::Keep
            ),
            "a,b,c,d\nnative,-0.05,,a b\n"
        );
    }

    #[test]
    fn guards_formulas_not_numbers() {
        assert_eq!(guard_formula("=HYPERLINK(\"x\")"), "'=HYPERLINK(\"x\")");
        assert_eq!(guard_formula("+cmd"), "'+cmd");
        assert_eq!(guard_formula("@SUM(A1)"), "'@SUM(A1)");
        assert_eq!(guard_formula("-x"), "'-x");
        assert_eq!(guard_formula("\tx"), "'\tx");
        assert_eq!(guard_formula("-0.05"), "-0.05");
        assert_eq!(guard_formula("+1e3"), "+1e3");
        assert_eq!(guard_formula("native"), "native");
        assert_eq!(
            text(&["name"], &[vec!["=HYPERLINK(\"x\")"]], Formulas::Guard),
            "name\n\"'=HYPERLINK(\"\"x\"\")\"\n"
        );
        assert_eq!(
            text(&["name"], &[vec!["=1+1"]], Formulas::Keep),
            "name\n=1+1\n"
        );
    }

    #[test]
    fn reads_back_what_it_wrote() {
        let rows = vec![
            vec!["run", "a,b", "say \"hi\""],
            vec!["", "two\nlines", "-0.05"],
        ];
        let bytes = write(&["x", "y", "z"], &rows, Formulas::Keep);
        let t = read(&bytes, Some(&["x", "y", "z"])).unwrap();
        assert_eq!(t.header, ["x", "y", "z"]);
        assert_eq!(t.rows, rows);
    }

    #[test]
    fn read_errors_name_the_line() {
        let e = read(b"x,y\n1,2\n3\n", None).unwrap_err();
        assert_eq!(e.to_string(), "CSV line 3: 1 fields where the header has 2");
        let e = read(b"x,z\n1,2\n", Some(&["x", "y"])).unwrap_err();
        assert_eq!(
            e.to_string(),
            "CSV header is [\"x\", \"z\"]; expected [\"x\", \"y\"]"
        );
    }
}
