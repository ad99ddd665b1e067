#pragma once
// The one conversion between the proto material (demcal.v1.Material) and the core's
// lab::MaterialModel, used by the coordinator (validation of factor paths and bounds) and by
// the worker (building the job's material). Metadata only: links no physics.
#include <cstdint>
#include <map>
#include <string>

#include "core/model/catalog.hpp"
#include "core/model/material.hpp"
#include "demcal/v1/campaign.pb.h"
#include "demcal/v1/worker.pb.h"

namespace demcal::rpc {

/// Builds and validates a material model; InputError names the field below `where`
/// ("spec.material.particle_law.normal.params.k1").
lab::MaterialModel to_material_model(const v1::Material& material, const std::string& where);

/// The proto form of a material model: to_material_model of it gives the model back, value for
/// value (every slot, size, shape and preparation parameter written out).
v1::Material to_material_message(const lab::MaterialModel& model);

/// The proto form of a contact law (every slot written out).
v1::ContactLaw to_law_message(const contact::ContactLawSpec& law);
/// The proto form of a bed preparation (its method and every parameter written out).
v1::Preparation to_preparation_message(const lab::PreparationSpec& preparation);

/// The spec with its material, and each test instance's own wall law and preparation, written out
/// in full as they read (to_material_message): two specs that read as the same campaign compare
/// equal, also when one was stored by an earlier build that left the material's defaults out.
/// InputError as to_material_model.
v1::CampaignSpec canonical_spec(const v1::CampaignSpec& spec);

/// The name of a test instance, which its responses and jobs carry ("<name>.<metric>"): its
/// `name`, or the lab test's when it has none.
std::string instance_name(const v1::LabTest& test);

/// The test instance of `spec` named `name` (instance_name); null when the spec has none.
const v1::LabTest* find_instance(const v1::CampaignSpec& spec, const std::string& name);

/// The material a test instance runs with: `material` with the instance's own wall law and bed
/// preparation, if any.
v1::Material instance_material(const v1::Material& material, const v1::LabTest& test);

/// The material of a job: its base material with the job's parameters set (factor values and
/// fixed parameters).
lab::MaterialModel job_material(const v1::JobSpec& job);

/// The material a job of campaign `spec` runs: the spec's material (with the instance's own wall
/// law and bed preparation, if `instance` is set) and `parameters` (fixed values, factors and tied
/// paths) set on it.
lab::MaterialModel job_material(const v1::CampaignSpec& spec, const v1::LabTest* instance,
                                const std::map<std::string, double>& parameters);

/// The simulation seed of a job: its seed, or 1 when it has none.
std::uint64_t job_seed(const v1::JobSpec& job);

lab::Settings to_settings(const google::protobuf::Map<std::string, double>& settings);

/// The parameters a run of the campaign sets on its material for the given factor values (path
/// to value): the spec's fixed values, the factors', and each factor's tied paths at its value.
std::map<std::string, double> run_parameters(const v1::CampaignSpec& spec,
                                             const std::map<std::string, double>& factors);

}  // namespace demcal::rpc
