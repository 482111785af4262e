//! A calendar date (UTC) from seconds since the Unix epoch, for a `SOURCE_DATE_EPOCH`-style param.

/// `YYYY-MM-DD` of the UTC day containing `epoch_s` (proleptic Gregorian calendar).
pub fn utc_date(epoch_s: i64) -> String {
    let days = epoch_s.div_euclid(86_400);
    // civil-from-days (Howard Hinnant's algorithm, written out from its description)
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = yoe + era * 400 + i64::from(month <= 2);
    format!("{year:04}-{month:02}-{day:02}")
}

#[cfg(test)]
mod tests {
    use super::utc_date;

    #[test]
    fn known_dates() {
        assert_eq!(utc_date(0), "1970-01-01");
        assert_eq!(utc_date(951_782_400), "2000-02-29");
        assert_eq!(utc_date(1_795_305_600), "2026-11-22");
        assert_eq!(utc_date(-1), "1969-12-31");
    }
}
