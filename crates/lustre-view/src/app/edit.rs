//! The editing actions the panels and the script share: the selection and the material
//! editor's draft of its material, a material parameter set through the render thread, the
//! method chosen (or refused on an adaptive-only scene), an object's own sample budget, a
//! scene camera as a bookmark.

use super::App;
use crate::camera::FlyCamera;
use crate::render::Request;
use crate::Method;
use lustre_scene::material_edit::{self, Field};
use lustre_scene::MaterialKind;

/// The material editor's state for the selected material.
pub(super) struct Draft {
    pub(super) material: usize,
    pub(super) fields: Vec<Field>,
    pub(super) spec: String,
}

impl App {
    pub(super) fn select(&mut self, mesh: Option<usize>) {
        self.selected = mesh;
        self.refresh_draft();
        if let (Some(m), Some(info)) = (mesh, &self.info) {
            if let Some((name, mat)) = info.meshes.get(m) {
                let mname = info.materials.get(*mat).map_or("?", |x| x.name.as_str());
                let text = format!("selected {name:?} (material {mname:?})");
                self.note(text, false);
            }
        }
    }

    pub(super) fn selected_material(&self) -> Option<usize> {
        let info = self.info.as_ref()?;
        info.meshes.get(self.selected?).map(|m| m.1)
    }

    pub(super) fn refresh_draft(&mut self) {
        self.draft = self.selected_material().and_then(|m| {
            let mat = self.info.as_ref()?.materials.get(m)?;
            let spec = match &mat.kind {
                MaterialKind::Spec(s) => s.spec.clone(),
                _ => String::new(),
            };
            Some(Draft {
                material: m,
                fields: material_edit::fields(mat),
                spec,
            })
        });
    }

    /// Asks the render thread to set a parameter of the selected material.
    pub(super) fn set_material(&mut self, field: &str, value: &str) {
        let Some(material) = self.selected_material() else {
            self.note("select an object first (click it)", true);
            return;
        };
        self.pending_edits += 1;
        let _ = self.to_render.send(Request::SetMaterial {
            material,
            field: field.to_string(),
            value: value.to_string(),
        });
    }

    /// Switches to method `m`, unless it is a walkthrough method and the scene is adaptive-only
    /// (said, and the method kept).
    pub(super) fn choose_method(&mut self, m: Method) {
        match self.walkthrough_refusal(m) {
            Some(why) => {
                let text = format!("{} method refused: {why}", m.name());
                self.note(text.clone(), true);
                self.status = text;
            }
            None => self.settings.frame.method = m,
        }
    }

    /// Why method `m` cannot show the scene: a walkthrough method on an adaptive-only scene.
    pub(super) fn walkthrough_refusal(&self, m: Method) -> Option<String> {
        let why = self.info.as_ref()?.no_walkthrough.as_ref()?;
        m.walkthrough().then(|| why.clone())
    }

    /// Gives mesh `mesh` its own sample budget (`None`: the global one).
    pub(super) fn set_object_samples(&mut self, mesh: usize, samples: Option<u32>) {
        if let Some(slot) = self
            .info
            .as_mut()
            .and_then(|i| i.object_samples.get_mut(mesh))
        {
            *slot = samples;
        }
        self.pending_edits += 1;
        let _ = self
            .to_render
            .send(Request::SetObjectSamples { mesh, samples });
    }

    pub(super) fn set_camera_named(&mut self, name: &str) -> bool {
        let Some(info) = &self.info else { return false };
        let Some(c) = info.cameras.iter().find(|c| c.name == name) else {
            return false;
        };
        let (w, h) = self.view_size;
        let aspect = if h > 0 {
            w as f64 / h as f64
        } else {
            16.0 / 9.0
        };
        self.camera = Some(FlyCamera::from_camera(c, aspect));
        true
    }
}
