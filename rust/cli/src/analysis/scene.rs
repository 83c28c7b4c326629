//! `sitar scene`: a session folder saved by the phone as a glTF 2.0 binary scene.

use std::path::PathBuf;

use anyhow::{Context, Result};
use sitar_core::Session;
use sitar_scene::SceneParts;

/// Writes the scene of a session folder (saved by the phone with `sitar_session_save`):
/// trajectory tube coloured by class, joints, camera frustums, start/stop, markers (both
/// styles) and depth-sampled surface points, converted to glTF's frame (right-handed, +Y up,
/// metres). Opens in Blender (File → Import → glTF 2.0) and in Unity with glTFast.
#[derive(clap::Args, Debug)]
#[command(after_help = "Example: sitar scene phone-session/ -o scene.glb")]
pub struct Args {
    /// The session folder (config.json, session.json, trajectory.txt, subtrajectories.csv,
    /// results.json once results arrived).
    session_dir: PathBuf,
    /// The .glb file to write.
    #[arg(short, long, value_name = "FILE", default_value = "scene.glb")]
    output: PathBuf,
}

pub fn run(args: Args) -> Result<()> {
    let session = Session::load(&args.session_dir).with_context(|| {
        format!(
            "cannot read the session folder {}",
            args.session_dir.display()
        )
    })?;
    let parts = SceneParts::from_session(&session);
    let glb = sitar_scene::to_glb(&parts)
        .with_context(|| format!("cannot export {}", args.session_dir.display()))?;
    std::fs::write(&args.output, &glb)
        .with_context(|| format!("cannot write {}", args.output.display()))?;
    println!(
        "{}: {} segments, {} joints, {} frustums, {} markers, {} surface points ({} bytes)",
        args.output.display(),
        parts.plan.segments.len(),
        parts.plan.joints.len(),
        parts.plan.frustums.len(),
        parts.markers.len(),
        parts.surface_points.len(),
        glb.len()
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use sitar_core::{DisplayRotation, SessionConfig};

    #[test]
    fn a_saved_session_folder_becomes_a_glb_and_a_bad_one_a_clear_error() {
        let dir = tempfile::tempdir().unwrap();
        let session = sitar_sim::Recording::demo(3.0, 30.0, 1)
            .unwrap()
            .phone_session(SessionConfig::default(), DisplayRotation::Deg0)
            .unwrap();
        let folder = dir.path().join("phone");
        session.save(&folder).unwrap();
        let output = dir.path().join("scene.glb");
        run(Args {
            session_dir: folder,
            output: output.clone(),
        })
        .unwrap();
        let glb = std::fs::read(&output).unwrap();
        let parsed = gltf::Gltf::from_slice(&glb).unwrap();
        let named = |name: &str| parsed.nodes().find(|n| n.name() == Some(name)).unwrap();
        assert_eq!(
            named("joints").children().count(),
            session.render_plan().joints.len()
        );
        let err = run(Args {
            session_dir: dir.path().join("missing"),
            output,
        })
        .unwrap_err();
        assert!(format!("{err:#}").contains("missing"), "{err:#}");
    }
}
