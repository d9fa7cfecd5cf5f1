//! `canif merge`: the shards of a campaign (`canif run --shard K/N`, on as
//! many machines as there are shards) joined into one run's reports, verdict
//! and, if asked, certificate.

use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use canif_harness::report::ShardPart;
use canif_spec::Catalogue;

use super::certify::write_certificate;
use super::run::finish;
use crate::stop::{stop, Stop};

/// A shard.json is the run's checks and failures: large for a soak, never this large.
const MAX_PART: u64 = 1 << 30;

/// What `canif merge` was asked for.
pub(crate) struct MergeArgs<'a> {
    pub shards: &'a [PathBuf],
    pub report: &'a Path,
    pub certificate: Option<&'a Path>,
    pub key: Option<&'a Path>,
}

pub(crate) fn merge(catalogue: &Catalogue, args: MergeArgs<'_>) -> Result<ExitCode, Stop> {
    if let Some(key) = args.key {
        // A key that cannot sign is found out before the merge, not after it.
        canif_harness::certificate::sign(b"", key).map_err(|e| stop!("--key {e}"))?;
    }
    let mut parts = Vec::new();
    for path in args.shards {
        let file = match path.is_dir() {
            true => path.join("shard.json"),
            false => path.clone(),
        };
        let part = read_part(&file)?;
        parts.push((file, part));
    }
    let report = canif_harness::report::merge(catalogue, parts).map_err(|e| stop!("{e}"))?;
    sayln!(
        "merged {} shard(s): {} profile(s), {} checks",
        args.shards.len(),
        report.profiles.len(),
        report
            .profiles
            .iter()
            .map(|p| p.ran.checks.len())
            .sum::<usize>()
    );
    let code = finish(catalogue, &report, args.report)?;
    if let Some(out) = args.certificate {
        write_certificate(catalogue, &report, out, args.key)?;
    }
    Ok(code)
}

/// One shard's part: a regular file (never a FIFO that blocks), of bounded size.
fn read_part(file: &Path) -> Result<ShardPart, Stop> {
    let missing = |e: std::io::Error| {
        stop!(
            "{}: {e}; give each shard's report folder (with the shard.json that `canif run --shard K/N` writes) or that file",
            file.display()
        )
    };
    if !std::fs::metadata(file).map_err(missing)?.is_file() {
        return Err(stop!("{}: not a regular file", file.display()));
    }
    let mut bytes = Vec::new();
    std::fs::File::open(file)
        .and_then(|f| f.take(MAX_PART + 1).read_to_end(&mut bytes))
        .map_err(|e| stop!("{}: {e}", file.display()))?;
    if bytes.len() as u64 > MAX_PART {
        return Err(stop!(
            "{}: larger than {MAX_PART} bytes; not a shard.json",
            file.display()
        ));
    }
    let text =
        String::from_utf8(bytes).map_err(|e| stop!("{}: not UTF-8 text ({e})", file.display()))?;
    ShardPart::parse(&text).map_err(|e| stop!("{}: {e}", file.display()))
}
