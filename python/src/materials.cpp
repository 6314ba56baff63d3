// Magnetization laws, magnetic materials and MPM materials.
#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include "arrays.h"
#include "bindings.h"
#include "lodestone/core/field/magnetization_law.h"
#include "lodestone/core/field/material.h"
#include "lodestone/core/mpm/material.h"

namespace lodestone::python {

void bindMaterials(py::module_& m) {
  py::enum_<LawKind>(m, "LawKind", "Kind of magnetization law.")
      .value("NONE", LawKind::None, "not magnetizable: M = 0")
      .value("LINEAR", LawKind::Linear, "M = chi (n/n0) H")
      .value("LANGEVIN", LawKind::Langevin, "M = n m L(k2 |H|) H/|H|, k2 = mu0 m/(kB T)");

  py::class_<MagneticMaterial>(m, "MagneticMaterial",
                               "A magnetization law plus the bulk micro-particle number density n0 (1/m^3) "
                               "that a filled cell carries. Made by the factories langevin_material, "
                               "linear_material, linearized, non_magnetic_material and paper_material.")
      .def_property_readonly("kind", [](const MagneticMaterial& mat) { return mat.law.kind; },
                             "The law's kind (LawKind).")
      .def_property_readonly("number_density", [](const MagneticMaterial& mat) { return mat.numberDensity; },
                             "n0 of the bulk material, micro-particles per m^3.")
      .def_property_readonly("moment", [](const MagneticMaterial& mat) { return mat.law.moment; },
                             "Micro-particle moment m, A*m^2 (Langevin; 0 otherwise).")
      .def_property_readonly("saturation", &MagneticMaterial::saturation,
                             "Saturation magnetization of the bulk material, A/m (inf for a linear law).")
      .def_property_readonly("low_field_susceptibility", &MagneticMaterial::lowFieldSusceptibility,
                             "Low-field susceptibility chi0 of the bulk material (dimensionless).")
      .def(
          "magnetization",
          [](const MagneticMaterial& mat, const py::object& H, double n) {
            const Vec3Input h(H, "H");
            py::array_t<double> out({py::ssize_t(h.size()), py::ssize_t(3)});
            Vec3d* o = reinterpret_cast<Vec3d*>(out.mutable_data());
            for (std::size_t p = 0; p < h.size(); ++p) o[p] = magnetization(mat.law, n, h.data()[p]);
            return out;
          },
          py::arg("H"), py::arg("n"),
          "M (A/m) of the law at fields H (A/m, shape (N, 3)) and micro-particle density n (1/m^3); "
          "returns shape (N, 3).")
      .def("describe", &MagneticMaterial::describe, "One line with units.")
      .def("__repr__", [](const MagneticMaterial& mat) { return "<MagneticMaterial " + mat.describe() + ">"; });

  m.def("langevin_material", &langevinMaterial, py::arg("moment"), py::arg("temperature"),
        py::arg("number_density"),
        "Langevin paramagnet: micro-particles of moment m (A*m^2) at temperature T (K) and bulk number "
        "density n0 (1/m^3).");
  m.def("linear_material", &linearMaterial, py::arg("chi"), py::arg("number_density"),
        "Linear material of susceptibility chi (>= 0) at bulk density n0 (1/m^3); where the transferred "
        "density is n, the local susceptibility is chi * n / n0.");
  m.def("linearized", &linearized, py::arg("material"),
        "The low-field linearisation of a Langevin material (chi = chi0, same n0).");
  m.def("non_magnetic_material", &nonMagneticMaterial, "A non-magnetic material (M = 0).");
  m.def("paper_material", &paperMaterial,
        "The paper's material (Sun et al. 2021, Table 2): m = 1.09e-19 A*m^2, T = 300 K, "
        "n0 ~ 7.59e23 1/m^3 (Ms ~ 8.27e4 A/m, chi0 ~ 0.91).");
  m.def("magnetization_from_remanence", &magnetizationFromRemanence, py::arg("remanence"),
        "Magnetization (A/m) of a permanent magnet of remanence Br (T): M = Br / mu0.");

  py::enum_<MpmModel>(m, "MpmModel", "Constitutive model of an MPM material.")
      .value("NEO_HOOKEAN_SOLID", MpmModel::NeoHookeanSolid)
      .value("VISCOUS_FLUID", MpmModel::ViscousFluid)
      .value("VISCOPLASTIC_FLUID", MpmModel::ViscoplasticFluid)
      .value("ELASTOPLASTIC_SOLID", MpmModel::ElastoplasticSolid);

  py::class_<MpmMaterial>(m, "MpmMaterial",
                          "An MPM material: constitutive model, density and moduli (SI), and an optional "
                          "magnetic material. Made by neo_hookean_solid, viscous_fluid, viscoplastic_fluid "
                          "and elastoplastic_solid.")
      .def_readonly("model", &MpmMaterial::model, "The constitutive model (MpmModel).")
      .def_readonly("density", &MpmMaterial::density, "Rest mass density, kg/m^3.")
      .def_readonly("mu", &MpmMaterial::mu, "Shear modulus (solids), Pa.")
      .def_readonly("lam", &MpmMaterial::lambda, "Lame parameter lambda (solids), Pa.")
      .def_readonly("viscosity", &MpmMaterial::viscosity, "Dynamic viscosity (fluids) or damping, Pa*s.")
      .def_readonly("bulk_modulus", &MpmMaterial::bulkModulus, "Bulk modulus (fluids), Pa.")
      .def_readonly("magnetic", &MpmMaterial::magnetic, "The magnetic material (MagneticMaterial).")
      .def_property(
          "surface_tension", [](const MpmMaterial& mat) { return mat.surfaceTension; },
          [](MpmMaterial& mat, double sigma) {
            MpmMaterial next = mat;
            next.surfaceTension = sigma;
            next.validate();
            mat = next;
          },
          "Surface tension coefficient of a fluid, N/m (0: none).")
      .def_property_readonly("is_magnetic", &MpmMaterial::isMagnetic, "True when the magnetic law is not NONE.")
      .def("describe", &MpmMaterial::describe, "One line with units.")
      .def("__repr__", [](const MpmMaterial& mat) { return "<MpmMaterial " + mat.describe() + ">"; });

  m.def("neo_hookean_solid", &neoHookeanSolid, py::arg("young_modulus"), py::arg("poisson_ratio"),
        py::arg("density"), py::arg("magnetic") = nonMagneticMaterial(),
        "Neo-Hookean solid from Young's modulus E (Pa, > 0), Poisson's ratio nu (in (-1, 0.5)) and "
        "density rho (kg/m^3, > 0), optionally magnetic.");
  m.def("viscous_fluid", &viscousFluid, py::arg("viscosity"), py::arg("bulk_modulus"), py::arg("density"),
        py::arg("magnetic") = nonMagneticMaterial(),
        "Viscous fluid from viscosity (Pa*s, >= 0), bulk modulus K (Pa, > 0) and density (kg/m^3, > 0).");
  m.def("viscoplastic_fluid", &viscoplasticFluid, py::arg("yield_stress"), py::arg("consistency"),
        py::arg("flow_index"), py::arg("max_viscosity"), py::arg("bulk_modulus"), py::arg("density"),
        py::arg("magnetic") = nonMagneticMaterial(),
        "Regularized Herschel-Bulkley fluid: yield stress (Pa), consistency (Pa*s^n), flow index n in "
        "(0, 2], viscosity cap (Pa*s), bulk modulus (Pa), density (kg/m^3).");
  m.def("elastoplastic_solid", &elastoplasticSolid, py::arg("young_modulus"), py::arg("poisson_ratio"),
        py::arg("yield_stress"), py::arg("viscosity"), py::arg("density"),
        py::arg("magnetic") = nonMagneticMaterial(),
        "Damped elastoplastic solid: Young's modulus (Pa), Poisson's ratio, von Mises yield stress (Pa), "
        "Kelvin-Voigt damping viscosity (Pa*s), density (kg/m^3).");
}

}  // namespace lodestone::python
