//! CSV reading for [`super::Tabulated`]: comments, header, one angle column
//! and one value column, with errors that name the source, line and
//! expectation.

use super::error::PhaseError;

/// Names accepted for the angle column (degrees), in order of preference.
pub(crate) const THETA_COLUMNS: [&str; 2] = ["theta_deg", "theta"];

/// A fault found while validating rows: `index` is the 0-based row (None for
/// the table as a whole) and `what` says what is wrong and what was expected.
#[derive(Debug)]
pub(crate) struct RowFault {
    pub index: Option<usize>,
    pub what: String,
}

/// The two columns read from a CSV text, with the line number of each row.
pub(crate) struct CsvColumns {
    /// Name of the angle column found in the header.
    pub theta_name: &'static str,
    /// Angles, degrees.
    pub theta_deg: Vec<f64>,
    /// Values of the requested column.
    pub p: Vec<f64>,
    /// 1-based line of each row.
    pub lines: Vec<usize>,
    /// Last line of the text (for faults of the table as a whole).
    pub last_line: usize,
}

/// Read the angle column and `column` from CSV `text`: lines whose first
/// non-blank character is `#` and blank lines are skipped; the first other
/// line is the header; fields are separated by commas and trimmed.
pub(crate) fn parse_csv(text: &str, column: &str, source_name: &str) -> Result<CsvColumns, PhaseError> {
    let error = |line: usize, what: String| PhaseError::Csv { source_name: source_name.to_string(), line, what };
    let mut rows =
        text.lines().enumerate().map(|(i, l)| (i + 1, l.trim())).filter(|(_, l)| !l.is_empty() && !l.starts_with('#'));
    let last_line = text.lines().count().max(1);

    // Header
    let Some((header_line, header)) = rows.next() else {
        return Err(error(
            last_line,
            format!("no header line: expected a header naming columns 'theta_deg' and '{column}'"),
        ));
    };
    let names: Vec<&str> = header.split(',').map(str::trim).collect();
    let Some((theta_index, theta_name)) =
        THETA_COLUMNS.iter().find_map(|&t| names.iter().position(|&n| n == t).map(|i| (i, t)))
    else {
        return Err(error(
            header_line,
            format!(
                "header has no 'theta_deg' column: expected the scattering angle in degrees \
                 under 'theta_deg' or 'theta' (found: {})",
                names.join(", ")
            ),
        ));
    };
    let Some(p_index) = names.iter().position(|&n| n == column) else {
        return Err(error(header_line, format!("header has no column '{column}' (found: {})", names.join(", "))));
    };

    // Data rows
    let mut out = CsvColumns { theta_name, theta_deg: Vec::new(), p: Vec::new(), lines: Vec::new(), last_line };
    for (line, text) in rows {
        let fields: Vec<&str> = text.split(',').map(str::trim).collect();
        if fields.len() != names.len() {
            return Err(error(
                line,
                format!(
                    "found {} fields: expected {} as in the header (line {header_line})",
                    fields.len(),
                    names.len()
                ),
            ));
        }
        let number = |index: usize, name: &str| {
            fields[index].parse::<f64>().map_err(|_| {
                error(line, format!("{name} = '{}' is not a number: expected a decimal number", fields[index]))
            })
        };
        out.theta_deg.push(number(theta_index, theta_name)?);
        out.p.push(number(p_index, column)?);
        out.lines.push(line);
    }
    Ok(out)
}
