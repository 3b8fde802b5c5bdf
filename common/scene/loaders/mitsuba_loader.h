#pragma once
// Mitsuba 0.6 XML scenes (the subset the farm renders) to a SceneDescription in world space.
//
// Supported: <integrator> (maxDepth only), one perspective or thinlens <sensor> with <film> and
// <rfilter> (tent, box, gaussian), <bsdf> diffuse / twosided / dielectric / roughdielectric /
// conductor / roughconductor / plastic / roughplastic (declared at top level with an id and used
// through <ref>, or inline in a shape), bitmap <texture>s for a diffuse reflectance, <shape>
// rectangle / cube / sphere / obj / ply / serialized with an optional area <emitter>, one constant
// or envmap <emitter> (the environment), point and spot <emitter>s, and <transform> built from
// matrix, translate, scale, rotate, lookat. Anything else that would change the picture is an error
// rather than silently ignored: a render that quietly differs from the scene is worse than one
// that refuses to start.
//
// The XML, its lines, ids and values are MitsubaDocument's (mitsuba_document.h), an object's
// named parameters MitsubaProperties' (mitsuba_properties.h); the loader says what they mean.
#include <string>

#include "common/scene/loaders/scene_files.h"
#include "common/scene/scene_description.h"

namespace farm {

// Throws SceneLoadError for anything it cannot load faithfully. Mesh paths are relative to the
// directory of the XML file.
SceneDescription loadMitsubaScene(const std::string& path);

}  // namespace farm
