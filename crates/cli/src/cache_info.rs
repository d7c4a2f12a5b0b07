//! `ircache cache info FILE`: what an irradiance cache file holds.

use anyhow::Result;
use clap::Subcommand;
use ircache_render::irradiance_cache::file;
use std::path::PathBuf;

/// Cache file commands.
#[derive(Subcommand, Debug)]
pub enum CacheCommand {
    /// Print the header, the settings and the records per bounce level.
    Info {
        /// The cache file.
        file: PathBuf,
    },
}

/// Runs `ircache cache ...`.
pub fn run(cmd: &CacheCommand) -> Result<()> {
    let CacheCommand::Info { file: path } = cmd;
    let c = file::read(path)?;
    let p = &c.header.params;
    let mut per_level = vec![0usize; p.bounces.max(1) as usize];
    for (r, _) in &c.records {
        if let Some(n) = per_level.get_mut(r.level as usize) {
            *n += 1;
        }
    }
    let radiance = c.records.iter().filter(|(_, c)| c.is_some()).count();
    println!("{}", path.display());
    println!("  format version   {}", c.header.version);
    println!("  scene hash       {:016x}", c.header.scene_hash);
    println!(
        "  settings         accuracy {}, divisions {}, super-samples {}, resolution {}, bounces {}, \
         ambient value {:?}, gradients {}, formula {:?}",
        p.accuracy,
        p.divisions,
        p.supersamples,
        p.resolution,
        p.bounces,
        p.ambient_value.to_array(),
        p.gradients.name(),
        p.formula
    );
    println!(
        "  records          {} (per bounce level: {per_level:?}; {radiance} with radiance)",
        c.records.len()
    );
    if !c.volume.is_empty() {
        println!("  volumetric       {} records (in media)", c.volume.len());
    }
    if c.torn_bytes > 0 {
        println!(
            "  torn tail        {} bytes after the last intact record (cut off when the file is next written)",
            c.torn_bytes
        );
    }
    Ok(())
}
