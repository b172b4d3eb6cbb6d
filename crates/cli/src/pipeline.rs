//! The scans of a log on every core, in order: one thread reads the log a
//! chunk at a time ([`read_log_chunks`]: for a CARMEN log only its lines),
//! a second hands each chunk to the thread pool (`--threads`), where it is
//! parsed and worked on scan by scan, and the caller's thread takes the
//! results in log order. The three overlap, and each stage holds at most a
//! few chunks, so memory does not grow with the log.
//!
//! Invariants: the caller sees every scan in log order, once, with its
//! result; the results do not depend on the number of threads when `work`
//! computes each scan's result from that scan alone; an error (reading,
//! parsing or checking a record) comes after every scan before it has been
//! consumed, and is the error of a sequential read; and when `consume`
//! breaks, nothing after that scan is consumed and the other stages stop.

use pcaline_io::{IoError, LogChunk, LogOptions, LogRecord, ScanRecord, read_log_chunks};
use std::ops::ControlFlow;
use std::path::Path;
use std::sync::mpsc;

/// Scans read and worked on together: enough to keep every thread busy,
/// few enough that memory does not grow with the log.
pub const BATCH_SCANS: usize = 256;

/// Batches handed to the pool and not yet taken by the caller, at most.
const IN_FLIGHT: usize = 4;

/// A batch the pool works on, when done: its scans, their results, and the
/// error that ended its parse, if one did (the log ends there).
type Done<T> = (Vec<ScanRecord>, Vec<T>, Option<IoError>);

/// Runs `work` over the scans of `file` in batches on the thread pool and
/// `consume` on each scan and its result in log order, on this thread.
/// `work(first, scans)` gets a batch whose first scan is scan `first` of the
/// log (from 0) and returns one result per scan. Returns the number of
/// scans consumed, or the error that stopped the read.
pub fn for_each_scan<T: Send>(
    file: &Path,
    options: &LogOptions,
    work: impl Fn(usize, &[ScanRecord]) -> Vec<T> + Sync,
    mut consume: impl FnMut(ScanRecord, T) -> ControlFlow<()>,
) -> Result<usize, IoError> {
    let (raw_out, raw_in) = mpsc::sync_channel::<LogChunk>(2);
    // One receiver per batch, in log order; each batch's result arrives on
    // its own once the pool has worked on it.
    let (pending_out, pending_in) = mpsc::sync_channel::<mpsc::Receiver<Done<T>>>(IN_FLIGHT);
    std::thread::scope(|scope| {
        // Each stage stops at the first send that finds the next one gone.
        let reader = scope.spawn(move || {
            read_log_chunks(file, options, BATCH_SCANS, |chunk| {
                if raw_out.send(chunk).is_err() {
                    return ControlFlow::Break(());
                }
                ControlFlow::Continue(())
            })
        });
        let work = &work;
        // Batches are handed to the pool as they are read, up to
        // `IN_FLIGHT` ahead of the caller: the pool does not wait for one
        // batch's last scans before starting the next. The scope's body runs
        // on this thread (`in_place_scope`), not on a pool thread, so its
        // blocking receives and sends never take a worker from the pool
        // (with one thread, that was a deadlock).
        scope.spawn(move || {
            rayon::in_place_scope(|pool| {
                let mut first = 0;
                for chunk in raw_in {
                    let (done_out, done_in) = mpsc::sync_channel(1);
                    if pending_out.send(done_in).is_err() {
                        break;
                    }
                    let start = first;
                    first += chunk.scans();
                    pool.spawn(move |_| {
                        let mut scans = Vec::with_capacity(chunk.scans());
                        let parsed = chunk.parse(|record| {
                            if let LogRecord::Scan(s) = record {
                                scans.push(s);
                            }
                            ControlFlow::Continue(())
                        });
                        let results = work(start, &scans);
                        // The caller may have stopped: nothing to hand over.
                        let _ = done_out.send((scans, results, parsed.err()));
                    });
                }
            });
        });
        let mut consumed = 0;
        let mut failed = None;
        'batches: for done in pending_in {
            // A task that panicked drops its sender: the scope re-raises it.
            let Ok((batch, results, error)) = done.recv() else { break };
            for (scan, result) in batch.into_iter().zip(results) {
                consumed += 1;
                if consume(scan, result).is_break() {
                    break 'batches;
                }
            }
            if error.is_some() {
                failed = error;
                break;
            }
        }
        // Leaving the loop drops the receiver, which stops the other stages.
        let read = reader.join().unwrap_or_else(|panic| std::panic::resume_unwind(panic));
        match failed {
            Some(e) => Err(e),
            None => read.map(|()| consumed),
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use pcaline_io::read_log;

    /// A CARMEN log of `scans` FLASER lines in the system's temporary
    /// folder (line `bad_at + 1` with a range that is not a number),
    /// removed when dropped.
    struct TempLog(std::path::PathBuf);

    impl Drop for TempLog {
        fn drop(&mut self) {
            let _ = std::fs::remove_file(&self.0);
        }
    }

    fn log(scans: usize, bad_at: Option<usize>) -> TempLog {
        use std::sync::atomic::{AtomicUsize, Ordering};
        static NEXT: AtomicUsize = AtomicUsize::new(0);
        let path = std::env::temp_dir().join(format!(
            "pcaline-pipeline-{}-{}.clf",
            std::process::id(),
            NEXT.fetch_add(1, Ordering::Relaxed)
        ));
        let mut text = String::new();
        for k in 0..scans {
            let range = if bad_at == Some(k) { "x".to_string() } else { format!("{}", 1 + k % 7) };
            let ranges = format!(" {range}").repeat(180);
            text.push_str(&format!("FLASER 180{ranges} 0 0 0 0 0 0 {k} host {k}\n"));
        }
        std::fs::write(&path, text).unwrap();
        TempLog(path)
    }

    /// Every scan once, in order, with its own result, across batches.
    #[test]
    fn scans_arrive_in_order_with_their_results() {
        let log = log(3 * BATCH_SCANS + 17, None);
        let mut seen = Vec::new();
        let read = for_each_scan(
            &log.0,
            &LogOptions::default(),
            |first, scans| (first..first + scans.len()).collect(),
            |scan, index| {
                seen.push((index, scan.position));
                ControlFlow::Continue(())
            },
        );
        assert_eq!(read.unwrap(), 3 * BATCH_SCANS + 17);
        let want: Vec<(usize, usize)> = (0..3 * BATCH_SCANS + 17).map(|k| (k, k + 1)).collect();
        assert_eq!(seen, want);
    }

    /// A bad line is reported after every scan before it was consumed, with
    /// the line number a sequential read reports (it is parsed on the pool,
    /// in the second batch).
    #[test]
    fn a_read_error_comes_after_the_scans_before_it() {
        let bad = BATCH_SCANS + 5;
        let log = log(2 * BATCH_SCANS, Some(bad));
        let mut consumed = 0;
        let err = for_each_scan(
            &log.0,
            &LogOptions::default(),
            |_, scans| vec![(); scans.len()],
            |_, ()| {
                consumed += 1;
                ControlFlow::Continue(())
            },
        )
        .unwrap_err();
        assert_eq!(consumed, bad);
        let mut sequential = None;
        let _ = read_log(&log.0, &LogOptions::default(), |_| ControlFlow::Continue(()))
            .map_err(|e| sequential = Some(e.to_string()));
        assert_eq!(Some(err.to_string()), sequential);
        assert!(err.to_string().contains(&format!(":{}:", bad + 1)), "{err}");
    }

    /// A consumer that stops gets nothing more, and the run ends.
    #[test]
    fn a_consumer_that_breaks_stops_everything() {
        let log = log(4 * BATCH_SCANS, None);
        let mut consumed = 0;
        let read = for_each_scan(
            &log.0,
            &LogOptions::default(),
            |_, scans| vec![(); scans.len()],
            |_, ()| {
                consumed += 1;
                if consumed == 10 { ControlFlow::Break(()) } else { ControlFlow::Continue(()) }
            },
        );
        assert!(read.is_ok());
        assert_eq!(consumed, 10);
    }
}
