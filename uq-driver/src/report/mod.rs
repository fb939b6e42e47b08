//! Writers for CSV, JSON, plots and the HTML report.
