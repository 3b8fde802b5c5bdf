#include "common/scene/loaders/ply_reader.h"

#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <assimp/Importer.hpp>

namespace farm {

PlyMesh parsePly(const std::string& bytes) {
  if (bytes.compare(0, 4, "ply\n") != 0 && bytes.compare(0, 5, "ply\r\n") != 0)
    throw std::runtime_error("not a PLY file (it does not start with the line 'ply')");
  Assimp::Importer importer;
  // Only what a PLY needs: polygons to triangles, and nothing that invents geometry or normals
  // (the loader computes Mitsuba's smooth normals itself when the file has none).
  importer.SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE,
                              aiPrimitiveType_POINT | aiPrimitiveType_LINE);
  const aiScene* scene = importer.ReadFileFromMemory(bytes.data(), bytes.size(),
                                                     aiProcess_Triangulate | aiProcess_SortByPType |
                                                         aiProcess_JoinIdenticalVertices |
                                                         aiProcess_ValidateDataStructure,
                                                     "ply");
  if (!scene) {
    std::string reason = importer.GetErrorString();
    if (reason.empty()) reason = "unknown error";
    throw std::runtime_error(reason);
  }
  PlyMesh out;
  bool allNormals = true, allUvs = true;
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
    const aiMesh* mesh = scene->mMeshes[m];
    if (!(mesh->mPrimitiveTypes & aiPrimitiveType_TRIANGLE)) continue;
    allNormals = allNormals && mesh->HasNormals();
    allUvs = allUvs && mesh->HasTextureCoords(0);
  }
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
    const aiMesh* mesh = scene->mMeshes[m];
    if (!(mesh->mPrimitiveTypes & aiPrimitiveType_TRIANGLE)) continue;
    const uint32_t base = uint32_t(out.positions.size());
    for (unsigned v = 0; v < mesh->mNumVertices; ++v) {
      const aiVector3D& p = mesh->mVertices[v];
      out.positions.emplace_back(p.x, p.y, p.z);
      if (allNormals) {
        const aiVector3D& n = mesh->mNormals[v];
        out.normals.emplace_back(n.x, n.y, n.z);
      }
      if (allUvs) {
        const aiVector3D& t = mesh->mTextureCoords[0][v];
        out.uvs.emplace_back(t.x, t.y);
      }
    }
    for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
      const aiFace& face = mesh->mFaces[f];
      if (face.mNumIndices != 3) continue;  // sorted out above; a stray one is not a triangle
      for (int k = 0; k < 3; ++k) {
        if (face.mIndices[k] >= mesh->mNumVertices)
          throw std::runtime_error("a face refers to vertex " + std::to_string(face.mIndices[k]) +
                                   " of " + std::to_string(mesh->mNumVertices));
        out.indices.push_back(base + face.mIndices[k]);
      }
    }
  }
  if (out.indices.empty()) throw std::runtime_error("no triangles (only points or lines)");
  return out;
}

}  // namespace farm
