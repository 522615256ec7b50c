//! The generated binary's CSV (`t,q1,…`), and how far two runs differ.

/// The rows of the CSV (the header skipped), each `[t, x_1, …, x_N]`.
pub fn parse_csv(text: &str) -> Result<Vec<Vec<f64>>, String> {
    let mut lines = text.lines();
    let header = lines.next().ok_or("empty CSV")?;
    let columns = header.split(',').count();
    let mut rows = Vec::new();
    for (i, line) in lines.enumerate() {
        let row: Vec<f64> = line
            .split(',')
            .map(|v| v.parse::<f64>())
            .collect::<Result<_, _>>()
            .map_err(|e| format!("CSV row {}: {e}", i + 1))?;
        if row.len() != columns {
            return Err(format!(
                "CSV row {}: {} values, the header has {columns}",
                i + 1,
                row.len()
            ));
        }
        rows.push(row);
    }
    Ok(rows)
}

/// The largest `|x − x_ref| / max(|x_ref|, 1)` over every sample and state
/// component (the generated binary's measure against an exact solution).
/// The two runs must have the same sample times.
pub fn largest_difference(measured: &[Vec<f64>], reference: &[Vec<f64>]) -> Result<f64, String> {
    if measured.len() != reference.len() {
        return Err(format!(
            "{} samples against {} in the reference",
            measured.len(),
            reference.len()
        ));
    }
    let mut largest = 0.0_f64;
    for (row, truth) in measured.iter().zip(reference) {
        if row.len() != truth.len() || row.first() != truth.first() {
            return Err("the reference has other sample times or columns".to_string());
        }
        for (x, r) in row.iter().zip(truth).skip(1) {
            let difference = (x - r).abs() / r.abs().max(1.0);
            if !difference.is_finite() {
                return Ok(f64::INFINITY);
            }
            largest = largest.max(difference);
        }
    }
    Ok(largest)
}
