//! Paths of the shared scenes.
#![allow(dead_code)]

use std::path::PathBuf;

pub fn data() -> PathBuf {
    lustre_env::shared_data_dir()
}

pub fn hall_xml() -> PathBuf {
    data().join("scenes/modern_hall/mitsuba/scene.xml")
}

pub fn hall_gltf() -> PathBuf {
    data().join("scenes/modern_hall/gltf/staircase2.gltf")
}

pub fn cornell() -> PathBuf {
    data().join("scenes/cornell_box/cornell_box.obj")
}
