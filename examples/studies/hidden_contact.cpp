// examples/studies/hidden_contact.cpp - the hidden-region setup (radiosity/visibility/
// hidden_regions.h) with and without the contact filter: which polygons the octree finds in
// contact with each surface (find_contacts), and whether the masks that the solver
// computes from them (find_hidden with the lists: seed texels near the contacts, grown over
// the hidden ones) miss any texel that the full test (rays from every texel) finds hidden.
//
// The program reports the surfaces, the texels of all their masks, the surfaces in contact,
// those with hidden texels, the hidden texels that the filtered masks miss (by surface, with
// names: these are the filter's misses), and the seconds of both setups.
//
// Run:    hidden_contact SCENE [--csv]
//         e.g. build/examples/hidden_contact examples/scenes/cornell_box.scene
// Expect: no misses (exit status 1 otherwise).
#include <iostream>
#include <string>
#include <vector>

#include "examples/common/cli.h"
#include "octree/octree.h"
#include "radiosity/scene/scene_io.h"
#include "radiosity/scene/scene_octree.h"
#include "radiosity/visibility/hidden_regions.h"

namespace {

const char* usage =
    "usage: hidden_contact SCENE [--csv]\n"
    "  Runs the hidden-region test on every texel of every surface of SCENE, and the one the\n"
    "  solver runs (only near the polygons in contact, grown over what is hidden), and reports\n"
    "  the hidden texels the second misses (exit status 1 when there are any).\n"
    "  SCENE   a scene file, or an .obj or .mgf file (imported)\n"
    "  --csv   one CSV row\n";

int run(mbr::Args& args) {
    const bool csv = args.flag("--csv");
    std::vector<std::string> files = args.positional();
    args.finish();
    if (files.size() != 1) throw mbr::UsageError("expected one SCENE file");
    const std::string& path = files[0];
    const mbr::Scene scene = mbr::load_scene_file(path);
    const mbr::Octree octree = mbr::build_octree(scene);
    const int n = static_cast<int>(scene.surfaces.size());

    double t0 = mbr::now_seconds();
    const mbr::HiddenContacts contacts = mbr::find_contacts(octree, n);
    const double contact_seconds = mbr::now_seconds() - t0;

    int n_contact = 0, n_hidden = 0, n_missed = 0;
    long texels_hidden = 0, texels_missed = 0, texels = 0;
    double full_seconds = 0, filtered_seconds = contact_seconds;
    std::vector<std::string> missed;
    for (int i = 0; i < n; ++i) {
        const mbr::Surface& surface = scene.surfaces[size_t(i)].surface;
        t0 = mbr::now_seconds();
        const mbr::HiddenMask mask = mbr::find_hidden(surface, i, octree);
        full_seconds += mbr::now_seconds() - t0;
        texels += long(mask.resolution()) * mask.resolution();
        mbr::HiddenMask filtered;
        if (!contacts.occluders[size_t(i)].empty()) {
            ++n_contact;
            t0 = mbr::now_seconds();
            filtered = mbr::find_hidden(surface, i, octree, &contacts);
            filtered_seconds += mbr::now_seconds() - t0;
        }
        if (!mask.any()) continue;
        ++n_hidden;
        texels_hidden += mask.hidden_count();
        // A texel hidden in the full mask and not in the filtered one is a miss (the filtered
        // test casts the same rays where it casts any).
        const int r = mask.resolution();
        long misses = 0;
        for (int j = 0; j < r; ++j)
            for (int k = 0; k < r; ++k) {
                const double s = (k + 0.5) / r, t = (j + 0.5) / r;
                if (mask.hidden(s, t) && !filtered.hidden(s, t)) ++misses;
            }
        if (misses > 0) {
            ++n_missed;
            texels_missed += misses;
            missed.push_back(scene.surfaces[size_t(i)].name + " (" + std::to_string(misses) +
                             " of its " + std::to_string(mask.hidden_count()) +
                             " hidden texels)");
        }
    }
    if (csv) {
        mbr::Table table({"scene", "surfaces", "texels", "in_contact", "with_hidden", "missed",
                          "hidden_texels", "missed_texels", "full_s", "contact_s", "filtered_s"});
        table.add_row({path, std::to_string(n), std::to_string(texels), std::to_string(n_contact), std::to_string(n_hidden),
                   std::to_string(n_missed), std::to_string(texels_hidden),
                   std::to_string(texels_missed), mbr::cell_g(full_seconds, 3),
                   mbr::cell_g(contact_seconds, 3), mbr::cell_g(filtered_seconds, 3)});
        table.write_csv(std::cout);
    } else {
        std::cout << "scene          " << path << ": " << n << " surfaces, "
                  << octree.polygon_count() << " polygons\n"
                  << "in contact     " << n_contact << " surfaces (found in "
                  << mbr::cell_g(contact_seconds, 3) << " s)\n"
                  << "texels         " << texels << " in all the masks\n"
                  << "with hidden    " << n_hidden << " surfaces, " << texels_hidden
                  << " texels (the full test)\n"
                  << "missed         " << n_missed << " surfaces, " << texels_missed
                  << " texels\n";
        for (const std::string& m : missed) std::cout << "  " << m << "\n";
        std::cout << "setup seconds  full " << mbr::cell_g(full_seconds, 3) << ", filtered "
                  << mbr::cell_g(filtered_seconds, 3) << " (2 threads inside each mask)\n";
    }
    return n_missed == 0 ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
    return mbr::run_main(argc, argv, usage, run);
}
