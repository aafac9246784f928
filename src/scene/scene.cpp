#include "scene/scene.h"

#include <cmath>

#include "core/error.h"
#include "volume/vdb_mesh.h"

namespace vdbmarch {

bool crossedByShadowRays(const MaterialDesc& m) {
    return m.type == MaterialDesc::Type::Interface || (m.type == MaterialDesc::Type::Dielectric && m.ior == 1.f);
}

int glassSphereOf(const Scene& scene, int surface) {
    for (size_t i = 0; i < scene.glassSpheres.size(); ++i)
        if (scene.glassSpheres[i].surface == surface) return int(i);
    return -1;
}

bool hasBendingGlass(const Scene& scene) {
    for (const SurfaceInfo& s : scene.surfaces)
        if (s.material.type == MaterialDesc::Type::Dielectric && !crossedByShadowRays(s.material)) return true;
    return false;
}

int regionAtRayStart(const Scene& scene, const Ray& r) {
    SurfaceHit h;
    if (!scene.surfaceSet->intersect(r, 0.f, Infinity, h)) return Scene::WorldRegion;
    const SurfaceInfo& s = scene.surfaces[size_t(h.surface)];
    return dot(r.d, h.n) > 0 ? s.interiorRegion : s.exteriorRegion;
}

namespace {

// Whether p may lie inside one of the closed surfaces `around`: by the
// parity of each surface's crossings along three rays from p. Any odd count
// (or a walk cut short) says inside, so a ray grazing an edge errs on the
// safe side.
bool mayBeInside(const Scene& scene, const Vec3& p, const std::vector<int>& around) {
    const Vec3 dirs[3] = {normalize(Vec3(0.267f, 0.534f, 0.802f)), normalize(Vec3(-0.719f, 0.113f, -0.686f)),
                          normalize(Vec3(0.371f, -0.928f, 0.031f))};
    for (const Vec3& d : dirs) {
        std::vector<int> crossings(around.size(), 0);
        Ray r{p, d};
        float tMin = 0;
        int hits = 0;
        SurfaceHit h;
        while (scene.surfaceSet->intersect(r, tMin, Infinity, h)) {
            if (++hits > 100000) return true;
            for (size_t k = 0; k < around.size(); ++k) crossings[k] += h.surface == around[k];
            tMin = h.t * (1 + 1e-6f) + 1e-6f * scene.sceneScale;
        }
        for (int c : crossings)
            if (c % 2) return true;
    }
    return false;
}

// Whether the ball (center, radius) may lie inside or cross one of the
// closed surfaces `around` (radius 0: a point).
bool ballMayBeInside(const Scene& scene, const Vec3& center, float radius, const std::vector<int>& around) {
    bool near = mayBeInside(scene, center, around);
    if (radius > 0)
        for (int s : around) near = near || scene.surfaceSet->mayComeWithin(s, center, radius * 1.001f);
    return near;
}

// The spheres of refracting glass, uniformly scaled, that next-event
// estimation sees light through (strategies/sphere_caustics.h), empty or
// holding a medium.
void findGlassSpheres(Scene& scene) {
    for (size_t i = 0; i < scene.desc.surfaces.size(); ++i) {
        const SurfaceDesc& sd = scene.desc.surfaces[i];
        const SurfaceInfo& info = scene.surfaces[i];
        if (sd.shape != SurfaceDesc::Shape::Sphere || info.material.type != MaterialDesc::Type::Dielectric ||
            crossedByShadowRays(info.material))
            continue;
        // Uniform scale: three orthogonal columns of one length.
        const Mat4& m = sd.transform;
        double len[3], dots[3];
        for (int c = 0; c < 3; ++c) {
            const int c2 = (c + 1) % 3;
            len[c] = std::sqrt(m.m[0][c] * m.m[0][c] + m.m[1][c] * m.m[1][c] + m.m[2][c] * m.m[2][c]);
            dots[c] = m.m[0][c] * m.m[0][c2] + m.m[1][c] * m.m[1][c2] + m.m[2][c] * m.m[2][c2];
        }
        const double r = len[0];
        if (!(r > 0) || std::fabs(len[1] - r) > 1e-6 * r || std::fabs(len[2] - r) > 1e-6 * r) continue;
        if (std::fabs(dots[0]) > 1e-6 * r * r || std::fabs(dots[1]) > 1e-6 * r * r || std::fabs(dots[2]) > 1e-6 * r * r)
            continue;
        GlassSphere g;
        g.center = Vec3(float(m.m[0][3]), float(m.m[1][3]), float(m.m[2][3]));
        g.radius = float(r);
        g.ior = info.material.ior;
        g.surface = int(i);
        g.outside = info.exteriorRegion;
        g.inside = info.interiorRegion;
        g.emptyInside = scene.regions[size_t(g.inside)].media.empty();
        for (size_t j = 0; j < scene.surfaces.size(); ++j)
            if (j != i && scene.surfaceSet->mayComeWithin(int(j), g.center, g.radius)) g.emptyInside = false;
        for (const Light& l : scene.lights) {
            const LightSphere* ls = l.sphere();
            if (ls && length(ls->center - g.center) < g.radius + ls->radius) g.emptyInside = false;
        }
        scene.glassSpheres.push_back(g);
    }
}

// A path tracer cannot reach a delta light through refracting glass, except
// through glass spheres (Scene::deltaLightCaustics). In media the caustic
// photons give that light (docs/method.md, the reference path tracer); on
// diffuse surfaces nothing does: a render by one says what it misses.
void warnOfMissedCaustics(const Scene& scene) {
    const SceneDesc& desc = scene.desc;
    if (!isPathTracer(desc.render.method) || scene.deltaLightCaustics) return;
    bool deltaLight = false, diffuse = false;
    for (const Light& l : scene.lights) deltaLight = deltaLight || l.isDelta();
    for (const auto& s : desc.surfaces) diffuse = diffuse || s.material.type == MaterialDesc::Type::Diffuse;
    if (deltaLight && diffuse && hasBendingGlass(scene))
        warn(str(desc.file, ": the caustics that a delta light (point, spot, directional or collimated_quad) "
                            "casts through refracting glass onto diffuse surfaces are missing from a "
                            "unidirectional path tracer (in media the caustic photons give them), except "
                            "through glass spheres with experiments.sphere_caustics; use sphere lights where the "
                            "reference must converge"));
}

// Scene::sphereLightCausticPhotons.
bool gathersSphereLightCaustics(const Scene& scene) {
    const ExperimentSettings& x = scene.desc.experiments;
    if (!x.causticPhotons || !scene.hasSphereLights || !hasBendingGlass(scene)) return false;
    if (x.sphereCaustics && !scene.glassSpheres.empty()) return false;
    for (const auto& m : scene.media)
        if (!m->isVacuum() && !isBlack(m->sigma_s)) return true;
    return false;
}

// Scene::deltaLightCaustics.
bool connectsDeltaLightCaustics(const Scene& scene) {
    if (!scene.desc.experiments.sphereCaustics) return false;
    for (size_t i = 0; i < scene.surfaces.size(); ++i) {
        const SurfaceInfo& info = scene.surfaces[i];
        const bool bends = info.material.type == MaterialDesc::Type::Dielectric && !crossedByShadowRays(info.material);
        if (bends && glassSphereOf(scene, int(i)) < 0) return false;
    }
    bool delta = false;
    for (const Light& l : scene.lights) {
        if (!l.isDelta()) continue;
        delta = true;
        const CollimatedQuad* quad = l.collimatedQuad();
        for (const GlassSphere& g : scene.glassSpheres) {
            if (l.isPointLike()) {
                // Inside a sphere or outside all, off their surfaces (where
                // the connections' roots would not be found).
                if (!(std::fabs(length(l.desc().position - g.center) - g.radius) > 1e-4f * g.radius)) return false;
            } else if (quad) {
                // The quad outside every ball (its beam then enters from outside).
                if (!(length(quad->center - g.center) > g.radius + 0.5f * (length(quad->u) + length(quad->v))))
                    return false;
            }
        }
    }
    return delta;
}

// Scene::shadowRaysCanReach. A region is sealed when every surface that
// names it is closed, blocks shadow rays and has it as its interior (so the
// region lies inside those surfaces, bounded); a light is then out of reach
// when it lies outside all of them: any straight ray from the region to it
// crosses one.
void computeShadowReach(Scene& scene) {
    const size_t nLights = scene.lights.size(), nRegions = scene.regions.size();
    scene.shadowReach.assign(nRegions * (nLights + 1), 1);
    for (size_t r = 0; r < nRegions; ++r) {
        if (r == size_t(Scene::WorldRegion)) continue;
        std::vector<int> around;
        bool sealed = true;
        for (size_t s = 0; s < scene.surfaces.size(); ++s) {
            const SurfaceInfo& info = scene.surfaces[s];
            if (info.interiorRegion != int(r) && info.exteriorRegion != int(r)) continue;
            around.push_back(int(s));
            sealed = sealed && info.interiorRegion == int(r) && info.exteriorRegion != int(r) && info.closed &&
                     !crossedByShadowRays(info.material);
        }
        if (!sealed || around.empty()) continue;
        char* reach = &scene.shadowReach[r * (nLights + 1)];
        reach[nLights] = 0;  // the environment: outside every closed surface
        for (size_t i = 0; i < nLights; ++i) {
            const Light& l = scene.lights[i];
            Vec3 center;
            float radius;
            if (l.atInfinity()) reach[i] = 0;
            else if (l.emittingBall(center, radius)) reach[i] = ballMayBeInside(scene, center, radius, around);
            // Elsewhere (a collimated quad) the light may cross the surfaces anywhere.
        }
    }
}

}  // namespace

std::unique_ptr<Scene> buildScene(const SceneDesc& desc) {
    auto scene = std::make_unique<Scene>();
    scene->desc = desc;
    scene->camera = std::make_unique<Camera>(desc.camera);
    scene->environment = desc.environment.file.empty()
                             ? Environment(desc.background)
                             : Environment(desc.environment, str(desc.file, ": environment.file"));
    for (const auto& l : desc.lights) scene->lights.add(makeLight(l));
    for (const Light& l : scene->lights) scene->hasSphereLights = scene->hasSphereLights || l.sphere();

    // Media: a medium named as some surface's interior lives only there.
    std::vector<bool> isInterior(desc.media.size(), false);
    for (const auto& s : desc.surfaces)
        for (size_t i = 0; i < desc.media.size(); ++i)
            if (desc.media[i].name == s.interior) isInterior[i] = true;
    scene->regions.resize(2 + desc.media.size());
    BBox bounds;
    for (size_t i = 0; i < desc.media.size(); ++i) {
        const MediumDesc& md = desc.media[i];
        std::unique_ptr<Medium> m =
            md.type == MediumDesc::Type::Vdb ? loadVdbMedium(md) : makeHomogeneousMedium(md);
        if (!m->isVacuum() || m->hasEmission) {
            scene->regions[2 + i].media.push_back(int(i));
            if (!isInterior[i]) scene->regions[Scene::WorldRegion].media.push_back(int(i));
            if (md.type == MediumDesc::Type::Vdb) {
                scene->regions[2 + i].gridded = true;
                if (!isInterior[i]) scene->regions[Scene::WorldRegion].gridded = true;
            }
            if (md.type == MediumDesc::Type::Homogeneous && !md.hasBounds) {
                Color k = min(md.sigma_a + md.sigma_s, Color(1e30f));
                scene->regions[2 + i].unboundedSigmaT += k;
                if (!isInterior[i]) scene->regions[Scene::WorldRegion].unboundedSigmaT += k;
            }
            BBox b = m->worldBounds();
            if (b.isFinite()) bounds.expand(b);
        }
        if (md.hasEmission && isBlack(md.sigma_a))
            warn(str(desc.file, ": media[", i, "] (\"", md.name,
                     "\") has emission but sigma_a = 0: emission enters as sigma_a L_e, so it is invisible"));
        scene->media.push_back(std::move(m));
    }
    for (Region& region : scene->regions) {
        region.constant = !region.media.empty();
        for (int mi : region.media) {
            const MediumDesc& md = desc.media[size_t(mi)];
            region.emits = region.emits || scene->media[size_t(mi)]->hasEmission;
            region.coefficients += scene->media[size_t(mi)]->sigma_a + scene->media[size_t(mi)]->sigma_s;
            region.constant = region.constant && md.type == MediumDesc::Type::Homogeneous && !md.hasBounds &&
                              !scene->media[size_t(mi)]->hasEmission;
        }
    }

    // Surfaces.
    scene->surfaceSet = std::make_unique<SurfaceSet>();
    auto mediumIndex = [&](const std::string& name) {
        for (size_t i = 0; i < desc.media.size(); ++i)
            if (desc.media[i].name == name) return int(i);
        return -1;
    };
    for (size_t i = 0; i < desc.surfaces.size(); ++i) {
        const SurfaceDesc& sd = desc.surfaces[i];
        SurfaceInfo info;
        info.material = sd.material;
        if (!sd.interior.empty()) info.interiorRegion = 2 + mediumIndex(sd.interior);
        if (!sd.exterior.empty()) info.exteriorRegion = 2 + mediumIndex(sd.exterior);
        scene->surfaces.push_back(info);
        Transform xf(sd.transform, str(desc.file, ": surfaces[", i, "].transform").c_str());
        if (sd.shape == SurfaceDesc::Shape::Sphere) {
            scene->surfaceSet->addSphere(xf, int(i));
            for (int c = 0; c < 8; ++c)
                bounds.expand(xf.point(Vec3(c & 1 ? 1.f : -1.f, c & 2 ? 1.f : -1.f, c & 4 ? 1.f : -1.f)));
            continue;
        }
        TriangleMesh mesh;
        if (sd.shape == SurfaceDesc::Shape::Box) mesh = makeUnitBox();
        else if (sd.shape == SurfaceDesc::Shape::Mesh) mesh = loadMesh(sd.file);
        else mesh = meshVdbIsosurface(sd.file, sd.grid, sd.isovalue);
        transformMesh(mesh, [&](const Vec3& p) { return xf.point(p); });
        scene->surfaces.back().closed = isClosed(mesh);
        if (sd.shape == SurfaceDesc::Shape::Mesh && !isClosed(mesh)) {
            if (!sd.interior.empty())
                warn(str(desc.file, ": surfaces[", i, "] (", sd.file,
                         ") is not a closed mesh, but it names an interior medium: rays may leak in or out"));
        } else if (sd.shape == SurfaceDesc::Shape::Mesh) {
            orientOutward(mesh);
        }
        for (const auto& p : mesh.positions) bounds.expand(p);
        scene->surfaceSet->addMesh(std::move(mesh), int(i), sd.smoothNormals);
    }
    scene->surfaceSet->commit();
    for (const Light& l : scene->lights) {
        Vec3 center;
        float radius;
        if (!l.emittingBall(center, radius)) continue;
        if (radius > 0) {
            bounds.expand(center - Vec3(radius));
            bounds.expand(center + Vec3(radius));
        } else {
            bounds.expand(center);
        }
    }
    bounds.expand(desc.camera.position);
    scene->sceneScale = bounds.empty() ? 1.f : std::max(1e-3f, maxComponent(max(-bounds.lo, bounds.hi)));

    // Step: one voxel of the finest grid, else a tenth of the smallest mean free path.
    float voxel = Infinity, maxSigmaT = 0;
    for (const auto& m : scene->media) {
        if (m->isVacuum() && !m->hasEmission) continue;
        if (m->minVoxelSize() > 0) voxel = std::min(voxel, m->minVoxelSize());
        else maxSigmaT = std::max(maxSigmaT, maxComponent(m->sigma_a + m->sigma_s) * m->maxDensity());
    }
    float autoStep = std::isfinite(voxel) ? voxel : (maxSigmaT > 0 ? 0.1f / maxSigmaT : 1.f);
    scene->step = desc.render.step > 0 ? desc.render.step : autoStep;
    scene->shadowStep = desc.render.shadowStep > 0 ? desc.render.shadowStep : scene->step;
    computeShadowReach(*scene);
    findGlassSpheres(*scene);
    scene->deltaLightCaustics = connectsDeltaLightCaustics(*scene);
    scene->sphereLightCausticPhotons = gathersSphereLightCaustics(*scene);
    warnOfMissedCaustics(*scene);
    return scene;
}

}  // namespace vdbmarch
