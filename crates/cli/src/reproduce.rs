//! `pcaline reproduce`: the paper's Tables 1-3 and `ETh` experiment, with the
//! paper's values beside ours.

use crate::out::outln;
use crate::progress;
use anyhow::Result;
use clap::ValueEnum;
use pcaline_eval::{
    ETH_EXPERIMENTS, EthResult, FitRow, FitRowResult, TABLE1, TABLE2, TABLE3, run_eth, run_fit_row,
};
use serde::Serialize;

/// What to reproduce.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Which {
    /// Table 1: spacing and count, sigma 4 cm.
    Table1,
    /// Table 2: noise level.
    Table2,
    /// Table 3: outliers.
    Table3,
    /// Detection probability of a 0.75 m wall at 10 m against ETh.
    Eth,
    /// Everything.
    All,
}

/// Arguments of `pcaline reproduce`.
#[derive(Debug, clap::Args)]
#[command(after_help = "Examples:
  pcaline reproduce all                           Tables 1-3 and the ETh experiment
  pcaline reproduce table2 --runs 1000 --json")]
pub struct ReproduceArgs {
    /// What to reproduce.
    #[arg(value_enum, default_value_t = Which::All)]
    which: Which,
    /// Runs per table row (the paper: 10,000).
    #[arg(long, default_value_t = 10_000, value_parser = crate::count_at_least_one)]
    runs: usize,
    /// Runs of the ETh experiment (the paper: 100,000).
    #[arg(long, default_value_t = 100_000, value_parser = crate::count_at_least_one)]
    eth_runs: usize,
    /// Random seed.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Print JSON instead of tables.
    #[arg(long)]
    json: bool,
}

#[derive(Debug, Serialize)]
struct RowOut {
    table: u8,
    spacing_m: f64,
    n: usize,
    length_m: f64,
    sigma_m: f64,
    outlier_fraction: f64,
    runs: usize,
    paper_err_pca_m: f64,
    err_pca_m: f64,
    err_ls_m: f64,
    paper_rel_diff_percent: f64,
    rel_diff_percent: f64,
    paper_t_pca_ms: Option<f64>,
    paper_t_ls_ms: Option<f64>,
    t_pca_us: f64,
    t_ls_us: f64,
}

#[derive(Debug, Serialize)]
struct EthOut {
    eth: f64,
    points: usize,
    runs: usize,
    detected: usize,
    percent: f64,
    paper_percent: f64,
}

/// Runs `pcaline reproduce`.
pub fn run(args: &ReproduceArgs, quiet: bool) -> Result<()> {
    let tables: Vec<(u8, &[FitRow])> = [(1u8, &TABLE1[..]), (2, &TABLE2[..]), (3, &TABLE3[..])]
        .into_iter()
        .filter(|(t, _)| {
            args.which == Which::All
                || matches!(
                    (t, args.which),
                    (1, Which::Table1) | (2, Which::Table2) | (3, Which::Table3)
                )
        })
        .collect();
    let mut rows = Vec::new();
    let total: usize = tables.iter().map(|(_, r)| r.len()).sum();
    let bar = progress::bar(total as u64, "rows", quiet);
    for (t, table) in &tables {
        for row in table.iter() {
            rows.push((*t, run_fit_row(row, args.runs, args.seed)));
            bar.inc(1);
        }
    }
    bar.finish_and_clear();
    let eth: Vec<EthResult> = if matches!(args.which, Which::Eth | Which::All) {
        ETH_EXPERIMENTS.iter().map(|e| run_eth(e, args.eth_runs, args.seed)).collect()
    } else {
        Vec::new()
    };

    if args.json {
        let rows: Vec<RowOut> = rows.iter().map(|(t, r)| row_out(*t, r)).collect();
        let eth: Vec<EthOut> = eth.iter().map(eth_out).collect();
        outln!(
            "{}",
            serde_json::to_string_pretty(&serde_json::json!({ "rows": rows, "eth": eth }))?
        )?;
        return Ok(());
    }
    for (t, _) in &tables {
        print_table(*t, rows.iter().filter(|(tt, _)| tt == t).map(|(_, r)| r))?;
    }
    if !eth.is_empty() {
        outln!("ETh experiment: a 0.75 m wall at 10 m, 0.25° beams, sigma 4 cm across it")?;
        outln!("{:>6} {:>7} {:>9} {:>10} {:>10}", "ETh", "points", "runs", "paper %", "ours %")?;
        for e in &eth {
            outln!(
                "{:>6} {:>7} {:>9} {:>10.2} {:>10.3}",
                e.experiment.eth,
                e.points,
                e.runs,
                e.experiment.paper_percent,
                e.percent()
            )?;
        }
    }
    Ok(())
}

fn row_out(table: u8, r: &FitRowResult) -> RowOut {
    RowOut {
        table,
        spacing_m: r.row.spacing_m,
        n: r.row.n,
        length_m: r.row.length_m(),
        sigma_m: r.row.sigma_m,
        outlier_fraction: r.row.outlier_fraction,
        runs: r.runs,
        paper_err_pca_m: r.row.paper_err_pca_m,
        err_pca_m: r.err_pca_m,
        err_ls_m: r.err_ls_m,
        paper_rel_diff_percent: r.row.paper_rel_diff_percent,
        rel_diff_percent: r.rel_diff_percent,
        paper_t_pca_ms: r.row.paper_times_ms.map(|t| t.0),
        paper_t_ls_ms: r.row.paper_times_ms.map(|t| t.1),
        t_pca_us: r.t_pca_ns / 1e3,
        t_ls_us: r.t_ls_ns / 1e3,
    }
}

fn eth_out(e: &EthResult) -> EthOut {
    EthOut {
        eth: e.experiment.eth,
        points: e.points,
        runs: e.runs,
        detected: e.detected,
        percent: e.percent(),
        paper_percent: e.experiment.paper_percent,
    }
}

fn print_table<'a>(table: u8, rows: impl Iterator<Item = &'a FitRowResult>) -> anyhow::Result<()> {
    let title = match table {
        1 => "Table 1: PCA vs LS over spacing and count (sigma 4 cm)",
        2 => "Table 2: PCA vs LS over noise (n 20, spacing 5 cm, L 1 m)",
        _ => "Table 3: PCA vs LS over outliers (n 200, spacing 2.5 cm, L 5 m, sigma 4 cm)",
    };
    outln!("{title}")?;
    outln!(
        "{:>6} {:>5} {:>5} {:>6} {:>5} | {:>9} {:>9} | {:>10} {:>10} | {:>11} {:>11} | {:>9} {:>9}",
        "x_s m",
        "n",
        "L m",
        "sigma",
        "P_O",
        "Err paper",
        "Err ours",
        "rel% paper",
        "rel% ours",
        "t PCA paper",
        "t LS paper",
        "t PCA us",
        "t LS us"
    )?;
    for r in rows {
        let (tp, tl) = r.row.paper_times_ms.map_or(("-".to_string(), "-".to_string()), |(a, b)| {
            (format!("{a:.2} ms"), format!("{b:.2} ms"))
        });
        outln!(
            "{:>6} {:>5} {:>5} {:>6} {:>5} | {:>9.3} {:>9.4} | {:>10.2e} {:>10.2e} | {:>11} {:>11} | {:>9.3} {:>9.3}",
            r.row.spacing_m,
            r.row.n,
            r.row.length_m(),
            r.row.sigma_m,
            r.row.outlier_fraction,
            r.row.paper_err_pca_m,
            r.err_pca_m,
            r.row.paper_rel_diff_percent,
            r.rel_diff_percent,
            tp,
            tl,
            r.t_pca_ns / 1e3,
            r.t_ls_ns / 1e3
        )?;
    }
    outln!()?;
    Ok(())
}
