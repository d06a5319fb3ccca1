//! risotto's scene-file loader: TOML scene files ([`scene_file`]), Mitsuba 3 XML and
//! pbrt-v4 scenes converted to TOML ([`import`]), the material registry by
//! type name and the conversion of a scene description into a scene world ([`load`]), the
//! built-in media's parameters ([`media_params`]), and the readers of the files scenes
//! reference: density grids (`.vol`, and OpenVDB with the default `vdb` feature), image
//! textures and environment maps.

mod coated_params;
pub mod grid_file;
pub mod import;
pub mod load;
pub mod media_params;
pub mod mesh_file;
mod mix_params;
mod rough_params;
pub mod scene_file;
pub mod side_file;
pub mod surface_params;
pub mod texture_file;
