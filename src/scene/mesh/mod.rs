//! TEMPORARY stub: replaced by the mesh-loading branch.
use glam::Vec3;
use std::path::Path;
pub struct MeshData {
    pub positions: Vec<Vec3>,
    pub normals: Option<Vec<Vec3>>,
    pub indices: Vec<[u32; 3]>,
}
#[derive(thiserror::Error, Debug)]
pub enum MeshError {
    #[error("{0}")]
    Other(String),
}
pub struct CleanReport {
    pub warnings: Vec<String>,
    pub removed_degenerate: usize,
    pub removed_duplicate: usize,
    pub repaired_normals: usize,
    pub computed_normals: bool,
}
pub fn load_mesh(path: &Path) -> Result<MeshData, MeshError> {
    Err(MeshError::Other(format!("{}: not yet", path.display())))
}
pub fn clean_mesh(mesh: MeshData, _label: &str) -> Result<(MeshData, CleanReport), MeshError> {
    Ok((
        mesh,
        CleanReport {
            warnings: vec![],
            removed_degenerate: 0,
            removed_duplicate: 0,
            repaired_normals: 0,
            computed_normals: false,
        },
    ))
}
pub fn convert(_input: &Path, _output: &Path) -> Result<CleanReport, MeshError> {
    Err(MeshError::Other("not yet".into()))
}
