#include <stdexcept>

#include <assimp/Importer.hpp>
#include <assimp/config.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <fmt/format.h>
#include <fmt/std.h>

#include "mesh.h"

namespace tilevis::scene {

Mesh import_mesh(const std::filesystem::path& file) {
  if (!std::filesystem::is_regular_file(file)) throw std::runtime_error(fmt::format("{}: no such mesh file", file));
  Assimp::Importer importer;
  // Keep positions only, so that joining identical vertices really joins every
  // corner at the same position (OBJ/3DS split vertices by normal and texcoord).
  importer.SetPropertyInteger(AI_CONFIG_PP_RVC_FLAGS,
                              aiComponent_NORMALS | aiComponent_TANGENTS_AND_BITANGENTS | aiComponent_COLORS |
                                  aiComponent_TEXCOORDS | aiComponent_BONEWEIGHTS | aiComponent_ANIMATIONS |
                                  aiComponent_TEXTURES | aiComponent_LIGHTS | aiComponent_CAMERAS |
                                  aiComponent_MATERIALS);
  // Node transforms applied, but meshes kept apart (by default the step joins meshes that share a
  // material, and with materials removed that is all of them): a multi-mesh file's objects stay draws.
  importer.SetPropertyBool(AI_CONFIG_PP_PTV_KEEP_HIERARCHY, true);
  const aiScene* s = importer.ReadFile(file.string(), aiProcess_RemoveComponent | aiProcess_Triangulate |
                                                          aiProcess_JoinIdenticalVertices |
                                                          aiProcess_PreTransformVertices);
  if (!s || !s->mRootNode) throw std::runtime_error(fmt::format("{}: {}", file, importer.GetErrorString()));
  Mesh out;
  for (unsigned mi = 0; mi < s->mNumMeshes; ++mi) {
    const aiMesh* am = s->mMeshes[mi];
    Mesh part;
    part.positions.reserve(am->mNumVertices);
    for (unsigned v = 0; v < am->mNumVertices; ++v)
      part.positions.push_back({am->mVertices[v].x, am->mVertices[v].y, am->mVertices[v].z});
    for (unsigned f = 0; f < am->mNumFaces; ++f) {
      const aiFace& face = am->mFaces[f];
      if (face.mNumIndices != 3) continue;  // points and lines carry no area
      part.indices.insert(part.indices.end(), {face.mIndices[0], face.mIndices[1], face.mIndices[2]});
    }
    if (part.indices.empty()) continue;
    const size_t first = out.indices.size();
    out.append(part);
    out.parts.push_back({am->mName.length ? std::string(am->mName.C_Str()) : fmt::format("mesh{}", mi), first,
                         part.indices.size()});
  }
  if (out.indices.empty()) throw std::runtime_error(fmt::format("{}: no triangles", file));
  if (out.parts.size() == 1) out.parts.clear();
  return out;
}

}  // namespace tilevis::scene
