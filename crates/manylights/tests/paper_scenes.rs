//! The scene files of the paper's Table 1 (`scenes/paper/*.toml`) hold exactly what `manylights
//! bench` generates on Sponza (`PaperScene::add_to`).

use std::path::PathBuf;

use manylights::scene::{self, paper_scenes::PaperScene};

#[test]
fn scene_files_match_the_generated_scenes() {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..");
    let sponza = scene::load_path(&root.join("../shared/assets/sponza/Sponza.gltf")).unwrap();
    for paper in PaperScene::ALL {
        let file = scene::load_path(&root.join(format!("scenes/paper/{}.toml", paper.name()))).unwrap();
        let mut generated = sponza.clone();
        paper.add_to(&mut generated, 1).unwrap();
        let name = paper.name();
        assert_eq!(file.lights, generated.lights, "{name}: lights");
        assert_eq!(file.decals, generated.decals, "{name}: decals");
        assert_eq!(file.cameras[0].position(), generated.cameras[0].position(), "{name}: camera");
        let count = if paper.has_decals() { file.decals.len() } else { file.lights.len() };
        assert_eq!(count, paper.count(), "{name}: Sponza has at least 6 large flat surfaces");
    }
}
