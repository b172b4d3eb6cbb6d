//! Reading a CARMEN log: the first 1000 lines of `mit-csail.clf` (SICK,
//! 361 beams a `FLASER` line), parsed from memory, so the figure is the
//! parse alone, without the disk. The log comes from `$PCALINE_DATA`
//! (default `../shared/data`); the bench says so loudly when it is missing.

#![allow(clippy::print_stderr)] // the loud report of a missing dataset

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use pcaline_io::{CarmenReader, LogRecord};
use std::hint::black_box;
use std::path::{Path, PathBuf};

fn reading(c: &mut Criterion) {
    let data = std::env::var_os("PCALINE_DATA")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/data"));
    let log = data.join("mit-csail/mit-csail.clf");
    let Ok(text) = std::fs::read_to_string(&log) else {
        eprintln!("!!! {} not found (set PCALINE_DATA): reading bench skipped", log.display());
        return;
    };
    let head: String = text.lines().take(1000).flat_map(|l| [l, "\n"]).collect();
    let mut group = c.benchmark_group("read_carmen");
    group.throughput(Throughput::Bytes(head.len() as u64));
    group.bench_function("mit_csail_1000_lines", |b| {
        b.iter(|| {
            let reader = CarmenReader::new(
                black_box(head.as_bytes()),
                Path::new("t.clf"),
                Default::default(),
            );
            let scans = reader.filter(|r| matches!(r, Ok(LogRecord::Scan(_)))).count();
            black_box(scans)
        })
    });
    group.finish();
}

criterion_group!(benches, reading);
criterion_main!(benches);
