//! The egui panel: the method, its parameters, the IOR, the backend, the views, the pass times.

use refract_scene::registry::ParamKind;

use crate::display::PanelFrame;
use crate::{ErrorView, Viewer, pass_time};

impl Viewer {
    /// The panel (egui): method and its parameters, IOR, TIR policy, backend, views, frame time
    /// and the keys. Changes are applied after the frame's UI ran.
    pub(crate) fn panel(&mut self, width: u32, height: u32) -> Option<PanelFrame> {
        if !self.show_panel {
            return None;
        }
        let display = self.display.as_mut()?;
        let raw = display.egui_state.take_egui_input(&display.window);
        let mut method = self.method;
        let mut params = self.method_params[self.method];
        let mut ior = self.scene.refractor.ior();
        let mut use_gpu = self.use_gpu;
        let mut split = self.split;
        let mut error_view = self.error_view;
        let (ms, methods, has_gpu) = (self.last_ms, &self.methods, self.gpu.is_some());
        let gpu_passes = self
            .gpu_ms
            .map_or_else(String::new, |ms| format!("GPU passes {ms:.1} ms; "));
        let pass_lines: Vec<String> = self.pass_times.iter().map(pass_time).collect();
        let readback = if self.use_gpu && !self.shown_from_gpu {
            "read back to the CPU"
        } else if self.use_gpu {
            "drawn on the GPU, no readback"
        } else {
            "CPU frame"
        };
        let output = display.egui.run_ui(raw, |ui| {
            egui::Window::new("refract")
                .default_pos([8.0, 8.0])
                .resizable(false)
                .show(ui.ctx(), |ui| {
                    ui.label(format!(
                        "{ms:.1} ms / frame ({:.0} fps)",
                        1e3 / ms.max(1e-3)
                    ));
                    ui.label(format!("{gpu_passes}{readback}"));
                    for line in &pass_lines {
                        ui.label(format!("  {line}"));
                    }
                    egui::ComboBox::from_label("method (m/n)")
                        .selected_text(methods[method].name())
                        .show_ui(ui, |ui| {
                            for (i, id) in methods.iter().enumerate() {
                                ui.selectable_value(&mut method, i, id.name());
                            }
                        });
                    for spec in methods[method].info().params {
                        let Some(value) = params.get(spec.name) else {
                            continue;
                        };
                        match spec.kind {
                            ParamKind::Choice(choices) => {
                                let mut chosen = value.clone();
                                egui::ComboBox::from_label(spec.name)
                                    .selected_text(&chosen)
                                    .show_ui(ui, |ui| {
                                        for c in choices {
                                            ui.selectable_value(&mut chosen, (*c).to_owned(), *c);
                                        }
                                    });
                                if chosen != value {
                                    let _ = params.set(spec.name, &chosen, "panel");
                                }
                            }
                            ParamKind::Integer { min, max } => {
                                let mut v: u32 = value.parse().unwrap_or(min);
                                ui.add(egui::Slider::new(&mut v, min..=max).text(spec.name));
                                if v.to_string() != value {
                                    let _ = params.set(spec.name, &v.to_string(), "panel");
                                }
                            }
                        }
                    }
                    ui.add(
                        egui::Slider::new(&mut ior, refract_scene::scene::IOR_RANGE)
                            .logarithmic(true)
                            .text("IOR (i/k)"),
                    );
                    ui.horizontal(|ui| {
                        ui.label("backend (b)");
                        if has_gpu {
                            ui.radio_value(&mut use_gpu, true, "GPU");
                        }
                        ui.radio_value(&mut use_gpu, false, "CPU");
                    });
                    ui.checkbox(&mut split, "split view with the exact reference (v)");
                    ui.horizontal(|ui| {
                        ui.label("show (e)");
                        ui.radio_value(&mut error_view, ErrorView::Off, "image");
                        ui.radio_value(&mut error_view, ErrorView::Flip, "FLIP");
                        ui.radio_value(&mut error_view, ErrorView::T2, "T2 error");
                    });
                    ui.collapsing("keys", |ui| {
                        ui.label(
                            "left drag orbit · right drag pan · wheel zoom · r reset\n\
                             m/n method · b backend · i/k IOR · t TIR · v split · e error map\n\
                             p screenshot + metrics · h hide this panel · q quit",
                        );
                    });
                });
        });
        display
            .egui_state
            .handle_platform_output(&display.window, output.platform_output);
        let pixels_per_point = output.pixels_per_point;
        let jobs = display.egui.tessellate(output.shapes, pixels_per_point);
        // Apply what the panel changed.
        self.method = method;
        self.method_params[method] = params;
        self.use_gpu = use_gpu;
        self.split = split;
        self.error_view = error_view;
        if (ior - self.scene.refractor.ior()).abs() > 1e-6 {
            self.pending_ior = Some(ior);
        }
        Some(PanelFrame {
            jobs,
            textures: output.textures_delta,
            screen: egui_wgpu::ScreenDescriptor {
                size_in_pixels: [width, height],
                pixels_per_point,
            },
        })
    }
}
