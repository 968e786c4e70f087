#include "src/core/npz.h"

#include <gtest/gtest.h>
#include <sys/resource.h>
#include <zip.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "src/core/file_util.h"
#include "src/core/test_util.h"

namespace hairmvs {
namespace {

using testing_util::MakeTestDir;

void WriteBytes(const std::string& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary);
  out.write(bytes.data(), bytes.size());
}

// A zip with one entry stored (no compression), as numpy.savez writes it.
void WriteStoredZip(const std::string& path, const std::string& entry, const std::string& bytes) {
  int error = 0;
  zip_t* archive = zip_open(path.c_str(), ZIP_CREATE | ZIP_TRUNCATE, &error);
  ASSERT_NE(archive, nullptr);
  zip_source_t* source = zip_source_buffer(archive, bytes.data(), bytes.size(), 0);
  const zip_int64_t index = zip_file_add(archive, entry.c_str(), source, 0);
  ASSERT_GE(index, 0);
  zip_set_file_compression(archive, index, ZIP_CM_STORE, 0);
  ASSERT_EQ(zip_close(archive), 0);
}

std::string ExpectThrowMessage(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  ADD_FAILURE() << "no hairmvs::Error thrown";
  return "";
}

TEST(Npz, NpyRoundTripAllTypes) {
  const std::string dir = MakeTestDir("npy");
  const auto f4 = NpyArray::FromVector<float>({1.5f, -2.f, 3.25f, 0.f, 7.f, 8.f}, {2, 3});
  WriteNpy(JoinPaths(dir, "a.npy"), f4);
  const NpyArray back = ReadNpy(JoinPaths(dir, "a.npy"));
  EXPECT_EQ(back.dtype, "<f4");
  EXPECT_EQ(back.shape, (std::vector<size_t>{2, 3}));
  EXPECT_EQ(back.data, f4.data);
  EXPECT_FLOAT_EQ(back.Data<float>()[2], 3.25f);
  // The data starts on a 64-byte boundary, as numpy writes it.
  EXPECT_EQ((FormatNpy(f4).size() - f4.data.size()) % 64, 0u);

  const auto i8 = NpyArray::FromVector<int64_t>({0, 33, 66, int64_t(1) << 40});
  const NpyArray i8_back = ParseNpy(FormatNpy(i8).data(), FormatNpy(i8).size(), "mem");
  EXPECT_EQ(i8_back.dtype, "<i8");
  EXPECT_EQ(i8_back.ToVector<int64_t>()[3], int64_t(1) << 40);
  EXPECT_EQ(i8_back.ToVector<double>()[1], 33.0);

  const auto scalar = NpyArray::Scalar<int64_t>(960);
  const std::string scalar_bytes = FormatNpy(scalar);
  EXPECT_NE(scalar_bytes.find("'shape': ()"), std::string::npos);
  const NpyArray scalar_back = ParseNpy(scalar_bytes.data(), scalar_bytes.size(), "mem");
  EXPECT_TRUE(scalar_back.shape.empty());
  EXPECT_EQ(scalar_back.AsDouble(0), 960.0);

  const auto names = NpyArray::FromStrings({"g0_c.png", "h10.png", "\xc3\xa9"});
  EXPECT_EQ(names.dtype, "<U8");
  const std::string names_bytes = FormatNpy(names);
  const NpyArray names_back = ParseNpy(names_bytes.data(), names_bytes.size(), "mem");
  EXPECT_EQ(names_back.Strings(),
            (std::vector<std::string>{"g0_c.png", "h10.png", "\xc3\xa9"}));
  EXPECT_THROW(names_back.ToVector<float>("names"), Error);
  // Strings of at most one character ("<U1", as numpy writes them too; empty ones as well).
  for (const std::vector<std::string>& short_names :
       {std::vector<std::string>{"a", "b"}, std::vector<std::string>{"", ""}}) {
    const std::string bytes = FormatNpy(NpyArray::FromStrings(short_names));
    const NpyArray back = ParseNpy(bytes.data(), bytes.size(), "short.npy");
    EXPECT_EQ(back.dtype, "<U1");
    EXPECT_EQ(back.Strings(), short_names);
  }

  const auto u1 = NpyArray::FromVector<uint8_t>({0, 1, 2, 255});
  const auto i4 = NpyArray::FromVector<int32_t>({-5, 7});
  const auto f8 = NpyArray::FromVector<double>({0.1, 1e300});
  for (const NpyArray* a : {&u1, &i4, &f8}) {
    const std::string bytes = FormatNpy(*a);
    const NpyArray b = ParseNpy(bytes.data(), bytes.size(), "mem");
    EXPECT_EQ(b.dtype, a->dtype);
    EXPECT_EQ(b.data, a->data);
  }
  EXPECT_EQ(u1.ToVector<int>()[3], 255);
  EXPECT_EQ(i4.ToVector<double>()[0], -5.0);
}

TEST(Npz, NpzRoundTripDeflateAndStored) {
  const std::string dir = MakeTestDir("npz");
  std::vector<float> depth(40 * 30);
  for (size_t i = 0; i < depth.size(); ++i) depth[i] = 0.5f + 0.001f * (i % 17);
  std::map<std::string, NpyArray> arrays;
  arrays["depth"] = NpyArray::FromVector(depth, {30, 40});
  arrays["label"] = NpyArray::FromVector(std::vector<uint8_t>(1200, 2), {30, 40});
  arrays["names"] = NpyArray::FromStrings({"a.png", "bb.png"});
  const std::string path = JoinPaths(dir, "view.npz");
  WriteNpz(path, arrays);
  const auto back = ReadNpz(path);
  ASSERT_EQ(back.size(), 3u);
  EXPECT_EQ(back.at("depth").data, arrays["depth"].data);
  EXPECT_EQ(back.at("depth").shape, (std::vector<size_t>{30, 40}));
  EXPECT_EQ(back.at("label").dtype, "|u1");
  EXPECT_EQ(back.at("names").Strings()[1], "bb.png");
  // Deflated: much smaller than the raw payload.
  EXPECT_LT(std::filesystem::file_size(path), 1200u * 5);
  EXPECT_THROW(NpzEntry(back, "normals", path), Error);

  const std::string stored = JoinPaths(dir, "stored.npz");
  WriteStoredZip(stored, "x.npy", FormatNpy(arrays["depth"]));
  EXPECT_EQ(ReadNpz(stored).at("x").data, arrays["depth"].data);

  WriteNpz(JoinPaths(dir, "empty.npz"), {});
  EXPECT_TRUE(ReadNpz(JoinPaths(dir, "empty.npz")).empty());
}

TEST(Npz, ErrorsNameTheFile) {
  const std::string dir = MakeTestDir("errors");
  const std::string missing = JoinPaths(dir, "missing.npz");
  EXPECT_NE(ExpectThrowMessage([&] { ReadNpz(missing); }).find("missing.npz"), std::string::npos);

  const std::string not_zip = JoinPaths(dir, "not_zip.npz");
  WriteBytes(not_zip, "hello, this is not a zip archive at all");
  EXPECT_NE(ExpectThrowMessage([&] { ReadNpz(not_zip); }).find("not_zip.npz"), std::string::npos);

  // A truncated archive (the central directory cut off).
  std::map<std::string, NpyArray> arrays;
  arrays["a"] = NpyArray::FromVector(std::vector<float>(1000, 1.f));
  const std::string good = JoinPaths(dir, "good.npz");
  WriteNpz(good, arrays);
  const std::string bytes = ReadTextFile(good);
  const std::string truncated = JoinPaths(dir, "truncated.npz");
  WriteBytes(truncated, bytes.substr(0, bytes.size() / 2));
  EXPECT_NE(ExpectThrowMessage([&] { ReadNpz(truncated); }).find("truncated.npz"),
            std::string::npos);

  // A non-.npy entry.
  const std::string text_entry = JoinPaths(dir, "text_entry.npz");
  WriteStoredZip(text_entry, "readme.txt", "hello");
  EXPECT_NE(ExpectThrowMessage([&] { ReadNpz(text_entry); }).find("readme.txt"),
            std::string::npos);
  // A .npy entry that is not npy data.
  const std::string bad_npy = JoinPaths(dir, "bad_npy.npz");
  WriteStoredZip(bad_npy, "a.npy", "definitely not npy");
  EXPECT_NE(ExpectThrowMessage([&] { ReadNpz(bad_npy); }).find("bad_npy.npz:a.npy"),
            std::string::npos);

  // An entry whose bytes no longer match its CRC (a flipped bit in the payload, the length
  // unchanged): an error, not other depths.
  const std::string npy_bytes = FormatNpy(NpyArray::FromVector(std::vector<float>(256, 0.5f)));
  const std::string crc_path = JoinPaths(dir, "crc.npz");
  WriteStoredZip(crc_path, "a.npy", npy_bytes);
  std::string zipped = ReadTextFile(crc_path);
  const size_t payload = zipped.find(npy_bytes);
  ASSERT_NE(payload, std::string::npos);
  zipped[payload + npy_bytes.size() - 1] ^= 0x10;
  WriteBytes(crc_path, zipped);
  const std::string crc_message = ExpectThrowMessage([&] { ReadNpz(crc_path); });
  EXPECT_NE(crc_message.find("crc.npz:a.npy: corrupt entry: CRC error"), std::string::npos)
      << crc_message;

  // Fortran order.
  std::string fortran = FormatNpy(NpyArray::FromVector<float>({1, 2, 3, 4}, {2, 2}));
  fortran.replace(fortran.find("False"), 5, "True ");
  const std::string fortran_path = JoinPaths(dir, "fortran.npy");
  WriteBytes(fortran_path, fortran);
  const std::string message = ExpectThrowMessage([&] { ReadNpy(fortran_path); });
  EXPECT_NE(message.find("fortran.npy"), std::string::npos);
  EXPECT_NE(message.find("Fortran"), std::string::npos);

  // Truncated payload and trailing bytes.
  const std::string npy = FormatNpy(NpyArray::FromVector<float>({1, 2, 3, 4}));
  EXPECT_THROW(ParseNpy(npy.data(), npy.size() - 1, "short"), Error);
  const std::string longer = npy + "x";
  EXPECT_THROW(ParseNpy(longer.data(), longer.size(), "long"), Error);
  // Shapes whose product wraps around 64 bits (here to 0, which an empty payload would match)
  // or whose dimensions do not fit in 64 bits: named as such.
  auto npy_of_shape = [](const std::string& shape) {
    const std::string dict = "{'descr': '<f4', 'fortran_order': False, 'shape': " + shape +
                             ", }\n";
    return std::string("\x93NUMPY\x01\x00", 8) + static_cast<char>(dict.size() & 0xff) +
           static_cast<char>(dict.size() >> 8) + dict;
  };
  const std::string wraps = npy_of_shape("(4294967296, 4294967296)");
  EXPECT_NE(ExpectThrowMessage([&] { ParseNpy(wraps.data(), wraps.size(), "wraps.npy"); })
                .find("wraps.npy: shape (4294967296, 4294967296) is larger than any file"),
            std::string::npos);
  const std::string huge = npy_of_shape("(123456789012345678901,)");
  EXPECT_NE(ExpectThrowMessage([&] { ParseNpy(huge.data(), huge.size(), "huge.npy"); })
                .find("huge.npy: malformed shape"),
            std::string::npos);
  // String dtypes: a count that is missing, 0 (with a shape of 10^17 elements of no bytes) or
  // too long for any number are named as unsupported, with the file.
  for (const std::string descr : {"<U", "<U0", "<U99999999999999999999", ">U4", "<Ux"}) {
    std::string strings = npy_of_shape("(100000000000000000,)");
    strings.replace(strings.find("<f4"), 3, descr);
    strings[8] = static_cast<char>(strings.size() - 10);  // the header's length, updated
    const std::string message =
        ExpectThrowMessage([&] { ParseNpy(strings.data(), strings.size(), "names.npy"); });
    EXPECT_NE(message.find("names.npy: "), std::string::npos) << descr << ": " << message;
    EXPECT_NE(message.find(descr), std::string::npos) << descr << ": " << message;
  }
  // Unsupported dtype.
  std::string complex = npy;
  complex.replace(complex.find("<f4"), 3, "<c8");
  EXPECT_NE(ExpectThrowMessage([&] { ParseNpy(complex.data(), complex.size(), "cplx.npy"); })
                .find("cplx.npy"),
            std::string::npos);
}

// An entry whose stated size (in the local header and the central directory) is 4 GB while it
// holds 4 KB: an error naming the entry, without allocating what it states (1 GB of address
// space is enough here; the buffer was once sized from the stated size).
TEST(Npz, StatedSizeIsNotAllocatedUpFront) {
  // AddressSanitizer reserves terabytes of shadow address space: the 1 GiB RLIMIT_AS below
  // would stop it, not the reader. (GCC defines __SANITIZE_ADDRESS__; clang says it through
  // __has_feature.)
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "RLIMIT_AS cannot be applied under AddressSanitizer";
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
  GTEST_SKIP() << "RLIMIT_AS cannot be applied under AddressSanitizer";
#endif
#endif
  const std::string dir = MakeTestDir("stated_size");
  const std::string path = JoinPaths(dir, "big.npz");
  WriteStoredZip(path, "a.npy", FormatNpy(NpyArray::FromVector(std::vector<float>(1000, 0.5f))));
  std::string zipped = ReadTextFile(path);
  const std::string stated("\xfe\xff\xff\xff", 4);
  for (const auto& [signature, size_offset] :
       {std::pair<std::string, size_t>{"PK\x03\x04", 22}, {"PK\x01\x02", 24}}) {
    const size_t at = zipped.find(signature);
    ASSERT_NE(at, std::string::npos);
    zipped.replace(at + size_offset, 4, stated);
  }
  WriteBytes(path, zipped);
  EXPECT_EXIT(
      {
        rlimit limit{};
        getrlimit(RLIMIT_AS, &limit);
        limit.rlim_cur = std::min<rlim_t>(rlim_t{1} << 30, limit.rlim_max);
        setrlimit(RLIMIT_AS, &limit);
        try {
          ReadNpz(path);
        } catch (const Error& e) {
          std::fprintf(stderr, "%s\n", e.what());
          std::exit(std::string(e.what()).find("big.npz:a.npy: ") != std::string::npos ? 0 : 1);
        } catch (const std::exception& e) {
          std::fprintf(stderr, "%s\n", e.what());
          std::exit(2);
        }
        std::exit(3);
      },
      ::testing::ExitedWithCode(0), "big.npz:a.npy");
}

// The shared data sets' files, written by numpy itself.
TEST(Npz, ReadsNumpyWrittenGroundTruth) {
  const std::string gt = JoinPaths(HAIRMVS_SHARED_DATA_DIR, "synth_straight_gantry", "gt");
  if (!ExistsFile(JoinPaths(gt, "cameras.npz"))) GTEST_SKIP() << "no shared data at " << gt;
  const auto cameras = ReadNpz(JoinPaths(gt, "cameras.npz"));
  const NpyArray& names = cameras.at("names");
  EXPECT_EQ(names.shape, (std::vector<size_t>{32}));
  EXPECT_EQ(names.Strings()[0].substr(0, 2), "g0");
  EXPECT_EQ(cameras.at("R").shape, (std::vector<size_t>{32, 3, 3}));
  EXPECT_EQ(cameras.at("width").AsDouble(0), 960.0);
  const NpyArray offsets = ReadNpy(JoinPaths(gt, "strands_offsets.npy"));
  EXPECT_EQ(offsets.dtype, "<i8");
  EXPECT_EQ(offsets.shape, (std::vector<size_t>{40001}));
}

}  // namespace
}  // namespace hairmvs
