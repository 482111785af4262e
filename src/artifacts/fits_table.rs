//! fits.csv (output of `aggregate`): one row per single run, sorted by run, numbers as `{:.6e}`,
//! an unknown value as an empty field. `COLUMNS` is the contract; the writer is `fit::fits_csv`.

/// The columns of fits.csv, in order.
pub const COLUMNS: [&str; 11] = [
    "run", "material", "v0_mps", "v0_se", "mu", "mu_se", "T_s", "T_se", "t1_s", "rms_m", "status",
];

/// The header line of fits.csv (the columns joined by commas).
pub const HEADER: &str = "run,material,v0_mps,v0_se,mu,mu_se,T_s,T_se,t1_s,rms_m,status";

/// One row of fits.csv as read back (an empty or non-finite number is None).
#[derive(Clone, Debug, PartialEq)]
pub struct FitsRow {
    pub run: String,
    pub material: String,
    pub v0_mps: Option<f64>,
    pub v0_se: Option<f64>,
    pub mu: Option<f64>,
    pub mu_se: Option<f64>,
    pub t_s: Option<f64>,
    pub t_se: Option<f64>,
    pub t1_s: Option<f64>,
    pub rms_m: Option<f64>,
    /// `converged`, `max_iterations` or `failed`.
    pub status: String,
}

/// Read fits.csv; the header must be `HEADER` exactly.
pub fn parse(csv: &str) -> Result<Vec<FitsRow>, String> {
    let mut lines = csv
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty());
    match lines.next() {
        None => return Ok(Vec::new()),
        Some((_, h)) if h.trim() == HEADER => {}
        Some((_, h)) => {
            return Err(format!(
                "fits.csv: header `{}` is not `{HEADER}`; regenerate it with the aggregate stage",
                h.trim()
            ))
        }
    }
    let mut rows = Vec::new();
    for (i, line) in lines {
        let cells: Vec<&str> = line.split(',').map(str::trim).collect();
        if cells.len() != COLUMNS.len() {
            return Err(format!(
                "fits.csv line {}: {} fields, expected {}; regenerate it with the aggregate stage",
                i + 1,
                cells.len(),
                COLUMNS.len()
            ));
        }
        let num =
            |c: usize| -> Option<f64> { cells[c].parse::<f64>().ok().filter(|x| x.is_finite()) };
        rows.push(FitsRow {
            run: cells[0].to_string(),
            material: cells[1].to_string(),
            v0_mps: num(2),
            v0_se: num(3),
            mu: num(4),
            mu_se: num(5),
            t_s: num(6),
            t_se: num(7),
            t1_s: num(8),
            rms_m: num(9),
            status: cells[10].to_string(),
        });
    }
    Ok(rows)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn header_is_the_columns() {
        assert_eq!(HEADER, COLUMNS.join(","));
    }

    #[test]
    fn reads_rows_and_rejects_another_header() {
        let csv =
            format!("{HEADER}\nb,440c,-5e-2,1e-4,2.9e-1,,1.1e-1,4e-3,1e-2,1.1e-6,converged\n");
        let rows = parse(&csv).unwrap();
        assert_eq!(rows.len(), 1);
        assert_eq!((rows[0].v0_mps, rows[0].mu_se), (Some(-0.05), None));
        assert_eq!(rows[0].status, "converged");
        assert!(parse("run,material\n").unwrap_err().contains("regenerate"));
    }
}
