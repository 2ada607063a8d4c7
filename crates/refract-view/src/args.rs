//! The viewer's command line (`ViewArgs`) and its unattended scripts.

use std::path::PathBuf;

use anyhow::Context;
use refract_scene::MethodId;

/// Arguments of `refract view`.
#[derive(Debug, clap::Args)]
pub struct ViewArgs {
    /// A built-in scene, a .toml scene file or a .gltf/.glb file.
    #[arg(default_value = "sphere")]
    pub scene: std::ffi::OsString,
    /// The method shown first (`m`/`n` switch).
    #[arg(long, default_value = "wyman")]
    pub method: MethodId,
    /// `gpu` (default) or `cpu` (`b` switches).
    #[arg(long, default_value = "gpu")]
    pub backend: String,
    /// Window size `WxH` in physical pixels (64 to 4096 a side).
    #[arg(long, default_value = "800x600", value_parser = parse_size)]
    pub size: (u32, u32),
    /// Exit after this many frames (with `--screenshot`, written first).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=100000))]
    pub frames: Option<u32>,
    /// Actions applied one per frame (`docs/viewer.md`): `key K`, `orbit DX DY`, `pan DX DY`,
    /// `zoom STEPS`, `wait`.
    #[arg(long)]
    pub script: Option<PathBuf>,
    /// Where `p` (and the end of an unattended run) writes the screenshot PNG; the frame's
    /// metrics go beside it as `.json`.
    #[arg(long, default_value = "refract-view.png")]
    pub screenshot: PathBuf,
    /// Read every GPU frame back to the CPU and upload it to the window again (the viewer's
    /// path before frames stayed on the GPU), to measure what the readback costs.
    #[arg(long)]
    pub readback: bool,
}

pub(crate) fn parse_size(text: &str) -> Result<(u32, u32), String> {
    let err = || format!("`{text}`: expected WxH with sides from 64 to 4096");
    let (w, h) = text.split_once(['x', 'X']).ok_or_else(err)?;
    let (w, h) = (
        w.trim().parse::<u32>().map_err(|_| err())?,
        h.trim().parse::<u32>().map_err(|_| err())?,
    );
    if (64..=4096).contains(&w) && (64..=4096).contains(&h) {
        Ok((w, h))
    } else {
        Err(err())
    }
}

/// One scripted action.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Action {
    Key(String),
    Orbit(f32, f32),
    Pan(f32, f32),
    Zoom(f32),
    Wait,
}

pub(crate) fn parse_script(text: &str, origin: &str) -> anyhow::Result<Vec<Action>> {
    let mut actions = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let words: Vec<&str> = line.split_whitespace().collect();
        let number = |i: usize| -> anyhow::Result<f32> {
            words
                .get(i)
                .and_then(|w| w.parse::<f32>().ok())
                .filter(|v| v.is_finite() && v.abs() <= 1e4)
                .with_context(|| {
                    format!(
                        "{origin}:{}: `{line}`: expected a number within ±10000",
                        n + 1
                    )
                })
        };
        actions.push(match words[0] {
            "key" if words.len() == 2 => Action::Key(words[1].to_owned()),
            "orbit" => Action::Orbit(number(1)?, number(2)?),
            "pan" => Action::Pan(number(1)?, number(2)?),
            "zoom" => Action::Zoom(number(1)?),
            "wait" => Action::Wait,
            _ => anyhow::bail!(
                "{origin}:{}: `{line}`: expected key K, orbit DX DY, pan DX DY, zoom STEPS or wait",
                n + 1
            ),
        });
    }
    Ok(actions)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scripts_parse_and_errors_name_the_line() {
        let actions =
            parse_script("# comment\nkey m\norbit 10 -5\nzoom 2\nwait\n", "s").expect("ok");
        assert_eq!(
            actions,
            [
                Action::Key("m".into()),
                Action::Orbit(10.0, -5.0),
                Action::Zoom(2.0),
                Action::Wait
            ]
        );
        let err = parse_script("key m\nspin 3\n", "s.txt")
            .expect_err("bad")
            .to_string();
        assert!(err.contains("s.txt:2"), "{err}");
        assert!(parse_script("orbit nan 1\n", "s").is_err());
        assert_eq!(parse_size("320x240"), Ok((320, 240)));
        assert!(parse_size("10x10").is_err());
    }
}
