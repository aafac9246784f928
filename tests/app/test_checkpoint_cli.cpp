// Checkpoints through the command (docs/farm.md, "Checkpoints"): SIGTERM
// makes `render --checkpoint` save its state and exit with status 75,
// leaving no output; the same command resumes, writes an image bit-identical
// to an uninterrupted render and removes the checkpoint. A checkpoint of
// other settings, a missing --resume file and bad checkpoint options are
// refused with messages naming them, and nothing is written.
#include <gtest/gtest.h>

#include <map>

#include "image/exr_io.h"
#include "support/support.h"

using namespace vdbmarch;
using namespace vdbmarch::test;

namespace {

class CheckpointCli : public BadInput {
protected:
    std::vector<std::string> renderArgs(const std::string& out, int spp) const {
        return {"render", samplePath("cloud.json"), "-o", work(out), "--res", "24x16", "--spp", std::to_string(spp),
                "-q"};
    }
    // Runs `args` in the background, waits for its first checkpoint at
    // `checkpoint`, sends `signal` (`times` times, 50 ms apart), and returns the
    // shell's output, which ends with "status=<exit status>". The command
    // runs under GNU timeout (runShell), which passes each signal on twice,
    // to its child and to its process group, as wrappers on farms do.
    CliResult stopAfterFirstCheckpoint(const std::vector<std::string>& args, const std::string& checkpoint,
                                       const char* signal, int times = 1) const {
        std::string c = shellQuote(vdbmarchBinary());
        for (const std::string& a : args) c += " " + shellQuote(a);
        c += " & pid=$!; for i in $(seq 500); do [ -f " + shellQuote(checkpoint) + " ] && break; sleep 0.02; done;";
        for (int i = 0; i < times; ++i) c += str(i > 0 ? " sleep 0.05;" : "", " kill -", signal, " $pid;");
        c += " wait $pid; echo status=$?";
        return runShell(c, work(""), mRoot.path());
    }
};

TEST_F(CheckpointCli, SigtermSavesAndTheSameCommandResumesBitIdentical) {
    const CliResult whole = cli(renderArgs("whole.exr", 800));
    ASSERT_EQ(whole.exitCode, 0) << whole.err;

    std::vector<std::string> args = renderArgs("part.exr", 800);
    args.insert(args.end(), {"--checkpoint", work("ck"), "--checkpoint-every", "0.1"});
    const CliResult stopped = stopAfterFirstCheckpoint(args, work("ck"), "TERM");
    ASSERT_NE(stopped.out.find("status=75"), std::string::npos) << stopped.out << stopped.err;
    EXPECT_TRUE(fs::exists(work("ck")));
    EXPECT_FALSE(fs::exists(work("part.exr")));
    EXPECT_TRUE(tempLeftovers(work("")).empty());

    args.back() = "60";  // no further checkpoint is due: the resumed run only reads it
    args.erase(std::find(args.begin(), args.end(), "-q"));
    const CliResult resumed = cli(args);
    ASSERT_EQ(resumed.exitCode, 0) << resumed.err;
    EXPECT_CONTAINS(resumed.err, "resuming from " + work("ck"));
    EXPECT_FALSE(fs::exists(work("ck")));  // removed once the render is whole
    const CliResult same = cli({"compare", "--identical", work("part.exr"), work("whole.exr")});
    EXPECT_EQ(same.exitCode, 0) << same.out;
    // The header says what an uninterrupted render says (the time counts
    // both runs).
    std::map<std::string, std::string> a, b;
    for (const auto& kv : readExrStringAttributes(work("part.exr"))) a[kv.first] = kv.second;
    for (const auto& kv : readExrStringAttributes(work("whole.exr"))) b[kv.first] = kv.second;
    for (const char* key : {"vdbmarch:spp", "vdbmarch:method", "vdbmarch:seed", "vdbmarch:renderHash",
                            "vdbmarch:photonPasses", "vdbmarch:timeBudget", "vdbmarch:scene"})
        EXPECT_EQ(a[key], b[key]) << key;
    EXPECT_EQ(a["vdbmarch:spp"], "800");
    EXPECT_GT(std::stod(a["vdbmarch:renderSeconds"]), 0.0);
}

// One stop request delivered several times within a second (a wrapper that
// forwards it, a process group signalled as a whole) is one request: the
// render still saves its checkpoint and exits 75, where a second request
// would end it at once.
TEST_F(CheckpointCli, ASignalDeliveredSeveralTimesStillSaves) {
    std::vector<std::string> args = renderArgs("part.exr", 2000);
    args.insert(args.end(), {"--checkpoint", work("ck"), "--checkpoint-every", "0.1"});
    const CliResult stopped = stopAfterFirstCheckpoint(args, work("ck"), "TERM", 3);
    ASSERT_NE(stopped.out.find("status=75"), std::string::npos) << stopped.out << stopped.err;
    EXPECT_TRUE(fs::exists(work("ck")));
    EXPECT_FALSE(fs::exists(work("part.exr")));
    EXPECT_TRUE(tempLeftovers(work("")).empty());
}

TEST_F(CheckpointCli, ForeignOrMissingCheckpointsAndBadOptionsAreRefused) {
    std::vector<std::string> args = renderArgs("part.exr", 2000);
    args.insert(args.end(), {"--checkpoint", work("ck"), "--checkpoint-every", "0.1"});
    const CliResult stopped = stopAfterFirstCheckpoint(args, work("ck"), "INT");
    ASSERT_NE(stopped.out.find("status=75"), std::string::npos) << stopped.out << stopped.err;

    // Other settings (another spp): refused, the checkpoint kept, nothing written.
    std::vector<std::string> other = renderArgs("part.exr", 1000);
    other.insert(other.end(), {"--checkpoint", work("ck")});
    expectCliError(cli(other), {work("ck"), "another scene or other settings"});
    EXPECT_TRUE(fs::exists(work("ck")));
    EXPECT_FALSE(fs::exists(work("part.exr")));

    std::vector<std::string> missing = renderArgs("part.exr", 10);
    missing.insert(missing.end(), {"--resume", work("nothing")});
    expectCliError(cli(missing), {"--resume", work("nothing"), "no such checkpoint"});

    std::vector<std::string> every = renderArgs("part.exr", 10);
    every.insert(every.end(), {"--checkpoint", work("ck2"), "--checkpoint-every", "0"});
    expectCliError(cli(every), {"--checkpoint-every 0", "positive"});
    std::vector<std::string> alone = renderArgs("part.exr", 10);
    alone.insert(alone.end(), {"--keep-checkpoint"});
    expectCliError(cli(alone), {"--keep-checkpoint", "--checkpoint FILE"});
    EXPECT_FALSE(fs::exists(work("part.exr")));
}

}  // namespace
