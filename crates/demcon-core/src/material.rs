//! Materials (one per phase) and their validation.

use crate::CoreError;
use crate::error::{positive, short_number};

/// The bulk properties of one phase of the continuous material, SI units.
#[derive(Debug, Clone, PartialEq)]
pub struct Material {
    /// Name used in scene files and messages.
    pub name: String,
    /// Thermal conductivity λ (W/(m·K)) at the reference temperature.
    pub conductivity: f64,
    /// Temperature coefficient β_λ of the conductivity (1/K): λ(T) = λ0 (1 + β_λ (T − T_λ));
    /// 0: constant.
    pub conductivity_temp_coeff: f64,
    /// Reference temperature T_λ of the conductivity (°C).
    pub conductivity_ref_temp: f64,
    /// λ(T) as a table of (T (°C), λ (W/(m·K))) points, linear between them and held beyond
    /// (a [`crate::TimeValue`] over temperature); overrides the temperature coefficient.
    pub conductivity_table: Option<crate::TimeValue>,
    /// An anisotropic conductivity: the tensor K (W/(m·K), symmetric positive definite, in the
    /// scene's axes) that replaces λ in conduction, scaled by λ(T)/λ0 with a temperature
    /// coefficient; `None`: isotropic λ.
    pub conductivity_tensor: Option<[[f64; 3]; 3]>,
    /// The tensor is given in each shaped inclusion's own frame (its z axis along the shape's
    /// axis, turned there by the shortest rotation): a particle of this material inside a
    /// shape conducts R K Rᵀ ([`Material::conductivity_along_in`]); `false`: the scene's axes.
    pub tensor_in_shape_frame: bool,
    /// Density of the continuous material ρ_c (kg/m³).
    pub density: f64,
    /// Specific heat c (J/(kg·K)).
    pub specific_heat: f64,
    /// Electric resistivity ρ_e at the reference temperature (Ω·m); `None` for a pure thermal material.
    pub resistivity: Option<f64>,
    /// Temperature coefficient β of the resistivity (1/K): ρ_e(T) = ρ_e0 (1 + β (T − T_ref)).
    pub resistivity_temp_coeff: f64,
    /// Reference temperature T_ref of the resistivity (°C or K, as the scene's temperatures).
    pub resistivity_ref_temp: f64,
}

impl Material {
    /// A thermal-only material.
    pub fn thermal(name: &str, conductivity: f64, density: f64, specific_heat: f64) -> Self {
        Self {
            name: name.to_string(),
            conductivity,
            conductivity_temp_coeff: 0.0,
            conductivity_ref_temp: 0.0,
            conductivity_tensor: None,
            tensor_in_shape_frame: false,
            conductivity_table: None,
            density,
            specific_heat,
            resistivity: None,
            resistivity_temp_coeff: 0.0,
            resistivity_ref_temp: 0.0,
        }
    }

    /// Thermal diffusivity a = λ / (ρ_c c) (m²/s).
    pub fn diffusivity(&self) -> f64 {
        self.conductivity / (self.density * self.specific_heat)
    }

    /// Thermal conductivity λ(T) (W/(m·K)) at temperature `t` (°C), possibly ≤ 0 outside the
    /// range the law holds in (the caller refuses it).
    pub fn conductivity_at(&self, t: f64) -> f64 {
        match &self.conductivity_table {
            Some(table) => table.at(t),
            None => {
                self.conductivity * (1.0 + self.conductivity_temp_coeff * (t - self.conductivity_ref_temp))
            }
        }
    }

    /// Whether the conductivity depends on temperature.
    pub fn conductivity_varies(&self) -> bool {
        self.conductivity_temp_coeff != 0.0
            || self.conductivity_table.as_ref().is_some_and(|t| !t.is_constant())
    }

    /// The conductivity along the unit vector `e` (W/(m·K)) at the reference temperature:
    /// eᵀ K e, or λ when isotropic.
    pub fn conductivity_along(&self, e: &crate::Vec3) -> f64 {
        match &self.conductivity_tensor {
            None => self.conductivity,
            Some(k) => (0..3)
                .map(|i| (0..3).map(|j| e[i] * k[i][j] * e[j]).sum::<f64>())
                .sum(),
        }
    }

    /// The conductivity along the unit vector `e` (W/(m·K)) of a particle whose shape has the
    /// unit axis `axis` (`None`: in no shape): with [`Material::tensor_in_shape_frame`], eᵀ R K
    /// Rᵀ e with R the shortest rotation taking z to the axis; [`Material::conductivity_along`]
    /// otherwise.
    pub fn conductivity_along_in(&self, e: &crate::Vec3, axis: Option<&crate::Vec3>) -> f64 {
        match axis {
            Some(a) if self.tensor_in_shape_frame => self.conductivity_along(&to_shape_frame(a, e)),
            _ => self.conductivity_along(e),
        }
    }

    /// Resistivity (Ω·m) at temperature `t`; `None` when the material has none.
    pub fn resistivity_at(&self, t: f64) -> Option<f64> {
        self.resistivity
            .map(|r0| r0 * (1.0 + self.resistivity_temp_coeff * (t - self.resistivity_ref_temp)))
    }

    /// Checks every property; errors name `materials[<name>].<field>`.
    pub fn validate(&self) -> Result<(), CoreError> {
        let f = |field: &str| format!("materials[{}].{field}", self.name);
        positive(&f("conductivity"), self.conductivity)?;
        positive(&f("density"), self.density)?;
        positive(&f("specific_heat"), self.specific_heat)?;
        if let Some(r) = self.resistivity {
            positive(&f("resistivity"), r)?;
        }
        if let Some(k) = &self.conductivity_tensor {
            check_tensor(&f("conductivity_tensor"), k)?;
        } else if self.tensor_in_shape_frame {
            return Err(CoreError::invalid(
                f("tensor_in_shape_frame"),
                true,
                "a `conductivity_tensor` to read in each shape's frame (an isotropic λ has none)",
            ));
        }
        if let Some(crate::TimeValue::Table(points)) = &self.conductivity_table {
            for (i, &(t, lam)) in points.iter().enumerate() {
                if !(lam.is_finite() && lam > 0.0) {
                    return Err(CoreError::invalid(
                        format!("{}[{i}]", f("conductivity_table")),
                        format!(
                            "({}, {})",
                            short_number(t.to_string()),
                            short_number(lam.to_string())
                        ),
                        "a conductivity > 0 (W/(m·K)) at every point",
                    ));
                }
                if i > 0 && t == points[i - 1].0 {
                    return Err(CoreError::invalid(
                        format!("{}[{i}]", f("conductivity_table")),
                        format!("T = {}", short_number(t.to_string())),
                        "temperatures strictly increasing (λ(T) has no jump)",
                    ));
                }
            }
        }
        for (field, v) in [
            ("conductivity_temp_coeff", self.conductivity_temp_coeff),
            ("conductivity_ref_temp", self.conductivity_ref_temp),
        ] {
            if !v.is_finite() {
                return Err(CoreError::invalid(f(field), v, "must be finite"));
            }
        }
        if !self.resistivity_temp_coeff.is_finite() {
            return Err(CoreError::invalid(
                f("resistivity_temp_coeff"),
                self.resistivity_temp_coeff,
                "must be finite (1/K)",
            ));
        }
        Ok(())
    }
}

/// Refuses a conductivity tensor that is not finite, symmetric (to 10⁻¹² of its largest entry)
/// and positive definite (Sylvester's criterion on its leading minors).
fn check_tensor(field: &str, k: &[[f64; 3]; 3]) -> Result<(), CoreError> {
    let big = k.iter().flatten().fold(0.0f64, |a, v| a.max(v.abs()));
    let show = || format!("{k:?}");
    if !k.iter().flatten().all(|v| v.is_finite()) || big == 0.0 {
        return Err(CoreError::invalid(
            field,
            show(),
            "a finite, non-zero tensor (W/(m·K))",
        ));
    }
    for (i, j) in [(0, 1), (0, 2), (1, 2)] {
        if (k[i][j] - k[j][i]).abs() > 1e-12 * big {
            return Err(CoreError::invalid(
                field,
                show(),
                format!(
                    "a symmetric tensor: K[{i}][{j}] = {} but K[{j}][{i}] = {}",
                    k[i][j], k[j][i]
                ),
            ));
        }
    }
    let m1 = k[0][0];
    let m2 = k[0][0] * k[1][1] - k[0][1] * k[1][0];
    let m3 = k[0][0] * (k[1][1] * k[2][2] - k[1][2] * k[2][1])
        - k[0][1] * (k[1][0] * k[2][2] - k[1][2] * k[2][0])
        + k[0][2] * (k[1][0] * k[2][1] - k[1][1] * k[2][0]);
    if !(m1 > 0.0 && m2 > 0.0 && m3 > 0.0) {
        return Err(CoreError::invalid(
            field,
            show(),
            format!(
                "a positive definite tensor (its leading minors {m1:.3e}, {m2:.3e}, {m3:.3e} must all be > 0)"
            ),
        ));
    }
    Ok(())
}

/// Materials indexed by phase id (phase 0 = the first material).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct MaterialTable {
    /// The materials; a particle of phase `p` is made of `materials[p]`.
    pub materials: Vec<Material>,
}

impl MaterialTable {
    /// A table; every material is validated.
    pub fn new(materials: Vec<Material>) -> Result<Self, CoreError> {
        if materials.is_empty() {
            return Err(CoreError::invalid(
                "materials",
                "[]",
                "at least one material is needed",
            ));
        }
        for m in &materials {
            m.validate()?;
        }
        Ok(Self { materials })
    }

    /// The material of phase `phase`, or an error if it is not defined.
    pub fn get(&self, phase: u16) -> Result<&Material, CoreError> {
        self.materials.get(phase as usize).ok_or_else(|| {
            CoreError::invalid(
                "phase",
                phase,
                format!("only {} material(s) are defined", self.materials.len()),
            )
        })
    }

    /// Phase id of the material called `name`.
    pub fn phase_of(&self, name: &str) -> Result<u16, CoreError> {
        self.materials
            .iter()
            .position(|m| m.name == name)
            .map(|p| p as u16)
            .ok_or_else(|| {
                let names: Vec<&str> = self.materials.iter().map(|m| m.name.as_str()).collect();
                CoreError::invalid(
                    "material",
                    name,
                    format!("defined materials are [{}]", names.join(", ")),
                )
            })
    }

    /// Checks that every phase used by `phases` has a material.
    pub fn check_phases(&self, phases: &[u16]) -> Result<(), CoreError> {
        match phases.iter().copied().max() {
            Some(p) => self.get(p).map(|_| ()),
            None => Ok(()),
        }
    }
}

/// Rᵀ `e`: the vector `e` in the frame whose z axis is the unit vector `axis`, R the shortest
/// rotation taking z to ±`axis` (a shape's axis has no sign: the one with a z component ≥ 0 is
/// taken, which keeps R away from the half turn).
pub fn to_shape_frame(axis: &crate::Vec3, e: &crate::Vec3) -> crate::Vec3 {
    let z = crate::Vec3::z();
    let a = if z.dot(axis) < 0.0 { -axis } else { *axis };
    let c = z.dot(&a);
    // R = I + [k]× + [k]×² / (1 + c), k = z × a; Rᵀ e = e − k × e + k × (k × e) / (1 + c).
    let k = z.cross(&a);
    let kx = k.cross(e);
    e - kx + k.cross(&kx) / (1.0 + c)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Vec3;

    #[test]
    fn the_shape_frame_puts_the_axis_on_z_and_keeps_lengths_and_angles() {
        let axes = [
            Vec3::z(),
            -Vec3::z(),
            Vec3::x(),
            Vec3::new(1.0, -2.0, 0.5).normalize(),
            Vec3::new(1e-9, 0.0, -1.0).normalize(),
        ];
        let e = Vec3::new(0.3, -0.4, 0.866).normalize();
        for a in axes {
            let sign = a.z.signum();
            assert!(
                (to_shape_frame(&a, &a) - sign * Vec3::z()).norm() < 1e-12,
                "{a:?}"
            );
            let f = to_shape_frame(&a, &e);
            assert!((f.norm() - 1.0).abs() < 1e-12);
            assert!((f.z - sign * a.dot(&e)).abs() < 1e-12, "{a:?}");
        }
        // A tensor about z in the frame of a shape along x conducts as one about x.
        let mut m = Material::thermal("fibre", 1.0, 1.0, 1.0);
        m.conductivity_tensor = Some([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 10.0]]);
        m.tensor_in_shape_frame = true;
        assert!((m.conductivity_along_in(&Vec3::x(), Some(&Vec3::x())) - 10.0).abs() < 1e-12);
        assert!((m.conductivity_along_in(&Vec3::x(), None) - 1.0).abs() < 1e-12);
        m.conductivity_tensor = None;
        assert!(
            m.validate()
                .unwrap_err()
                .to_string()
                .contains("tensor_in_shape_frame")
        );
    }

    #[test]
    fn validation() {
        let mut m = Material::thermal("steel", 33.0, 7800.0, 0.9);
        assert!(m.validate().is_ok());
        m.conductivity = -1.0;
        let e = m.validate().unwrap_err().to_string();
        assert!(
            e.contains("materials[steel].conductivity") && e.contains("-1"),
            "{e}"
        );
        let t = MaterialTable::new(vec![Material::thermal("a", 1.0, 1.0, 1.0)]).unwrap();
        assert!(t.get(1).is_err());
        assert!(t.phase_of("b").is_err());
        assert!(t.check_phases(&[0, 0]).is_ok());
    }
}
