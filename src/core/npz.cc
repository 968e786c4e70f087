#include "src/core/npz.h"

#include <zip.h>

#include <fstream>
#include <limits>
#include <memory>
#include <sstream>

#include "src/core/file_util.h"

namespace hairmvs {
namespace {

constexpr char kNpyMagic[] = "\x93NUMPY";
constexpr size_t kNpyMagicSize = 6;
// Longest string element read (<U65536): image names and the like, far below it.
constexpr unsigned long kMaxNpyStringChars = 65536;

// Item size of a numeric descr such as "<f4"; 0 for an unknown one.
size_t NumericItemSize(const std::string& dtype) {
  static const char* const kKnown[] = {"<f4", "<f8", "|u1", "|i1", "|b1", "<u2",
                                       "<i2", "<u4", "<i4", "<u8", "<i8"};
  for (const char* known : kKnown) {
    if (dtype == known) return static_cast<size_t>(dtype[2] - '0');
  }
  return 0;
}

// Characters per element of a string descr "<U<n>", n from 1 to kMaxNpyStringChars; 0 for any
// other descr.
size_t StringItemChars(const std::string& dtype) {
  const std::string count = dtype.size() > 2 ? dtype.substr(2) : "";
  if (dtype.rfind("<U", 0) != 0 || count.empty() || count.size() > 7 ||
      count.find_first_not_of("0123456789") != std::string::npos) {
    return 0;
  }
  const unsigned long chars = std::stoul(count);
  return chars <= kMaxNpyStringChars ? chars : 0;
}

// The value of `key` in a numpy header dict, as raw text up to the next top-level comma.
std::string HeaderValue(const std::string& header, const std::string& key,
                        const std::string& source) {
  const std::string quoted1 = "'" + key + "'";
  const std::string quoted2 = "\"" + key + "\"";
  size_t pos = header.find(quoted1);
  size_t len = quoted1.size();
  if (pos == std::string::npos) {
    pos = header.find(quoted2);
    len = quoted2.size();
  }
  THROW_IF(pos == std::string::npos,
           source << ": malformed .npy header (no '" << key << "'): " << header);
  pos = header.find(':', pos + len);
  THROW_IF(pos == std::string::npos, source << ": malformed .npy header: " << header);
  ++pos;
  while (pos < header.size() && header[pos] == ' ') ++pos;
  size_t end = pos;
  if (end < header.size() && header[end] == '(') {
    end = header.find(')', end);
    THROW_IF(end == std::string::npos, source << ": malformed shape in .npy header: " << header);
    ++end;
  } else {
    while (end < header.size() && header[end] != ',' && header[end] != '}') ++end;
  }
  return StripWhitespace(header.substr(pos, end - pos));
}

std::string Unquote(const std::string& s, const std::string& source) {
  THROW_IF(s.size() < 2 || (s.front() != '\'' && s.front() != '"') || s.back() != s.front(),
           source << ": expected a quoted string in the .npy header, found " << s);
  return s.substr(1, s.size() - 2);
}

void AppendUtf8(uint32_t cp, std::string* out) {
  if (cp < 0x80) {
    out->push_back(static_cast<char>(cp));
  } else if (cp < 0x800) {
    out->push_back(static_cast<char>(0xC0 | (cp >> 6)));
    out->push_back(static_cast<char>(0x80 | (cp & 0x3F)));
  } else if (cp < 0x10000) {
    out->push_back(static_cast<char>(0xE0 | (cp >> 12)));
    out->push_back(static_cast<char>(0x80 | ((cp >> 6) & 0x3F)));
    out->push_back(static_cast<char>(0x80 | (cp & 0x3F)));
  } else {
    out->push_back(static_cast<char>(0xF0 | (cp >> 18)));
    out->push_back(static_cast<char>(0x80 | ((cp >> 12) & 0x3F)));
    out->push_back(static_cast<char>(0x80 | ((cp >> 6) & 0x3F)));
    out->push_back(static_cast<char>(0x80 | (cp & 0x3F)));
  }
}

std::vector<uint32_t> DecodeUtf8(const std::string& s) {
  std::vector<uint32_t> cps;
  for (size_t i = 0; i < s.size();) {
    const auto c = static_cast<unsigned char>(s[i]);
    int extra = 0;
    uint32_t cp = c;
    if (c >= 0xF0) {
      extra = 3;
      cp = c & 0x07;
    } else if (c >= 0xE0) {
      extra = 2;
      cp = c & 0x0F;
    } else if (c >= 0xC0) {
      extra = 1;
      cp = c & 0x1F;
    }
    ++i;
    for (int k = 0; k < extra && i < s.size(); ++k, ++i) {
      cp = (cp << 6) | (static_cast<unsigned char>(s[i]) & 0x3F);
    }
    cps.push_back(cp);
  }
  return cps;
}

std::string ZipErrorString(int code) {
  zip_error_t error;
  zip_error_init_with_code(&error, code);
  std::string text = zip_error_strerror(&error);
  zip_error_fini(&error);
  return text;
}

}  // namespace

size_t NpyArray::NumElements() const {
  size_t n = 1;
  for (size_t d : shape) n *= d;
  return n;
}

size_t NpyArray::ItemSize() const {
  if (IsString()) {
    const size_t chars = StringItemChars(dtype);
    THROW_IF(chars == 0, "Unsupported numpy dtype " << dtype);
    return 4 * chars;
  }
  const size_t size = NumericItemSize(dtype);
  THROW_IF(size == 0, "Unsupported numpy dtype " << dtype);
  return size;
}

double NpyArray::AsDouble(size_t i) const {
  CHECK_LT(i, NumElements());
  const char* p = data.data() + i * ItemSize();
  auto load = [p](auto tag) {
    decltype(tag) v;
    std::memcpy(&v, p, sizeof(v));
    return static_cast<double>(v);
  };
  if (dtype == "<f4") return load(float());
  if (dtype == "<f8") return load(double());
  if (dtype == "|u1") return load(uint8_t());
  if (dtype == "|i1") return load(int8_t());
  if (dtype == "|b1") return load(uint8_t()) != 0 ? 1.0 : 0.0;
  if (dtype == "<u2") return load(uint16_t());
  if (dtype == "<i2") return load(int16_t());
  if (dtype == "<u4") return load(uint32_t());
  if (dtype == "<i4") return load(int32_t());
  if (dtype == "<u8") return load(uint64_t());
  if (dtype == "<i8") return load(int64_t());
  HAIRMVS_THROW("Not a numeric numpy dtype: " << dtype);
}

std::vector<std::string> NpyArray::Strings(const std::string& what) const {
  THROW_IF(!IsString(), what << ": expected a string (<U) array, found dtype " << dtype);
  const size_t chars = ItemSize() / 4;
  std::vector<std::string> out(NumElements());
  for (size_t i = 0; i < out.size(); ++i) {
    for (size_t c = 0; c < chars; ++c) {
      uint32_t cp;
      std::memcpy(&cp, data.data() + (i * chars + c) * 4, 4);
      if (cp == 0) break;  // numpy pads with NULs
      AppendUtf8(cp, &out[i]);
    }
  }
  return out;
}

NpyArray NpyArray::FromStrings(const std::vector<std::string>& strings) {
  std::vector<std::vector<uint32_t>> decoded;
  size_t max_chars = 1;
  for (const std::string& s : strings) {
    decoded.push_back(DecodeUtf8(s));
    max_chars = std::max(max_chars, decoded.back().size());
  }
  NpyArray array;
  array.dtype = "<U" + std::to_string(max_chars);
  array.shape = {strings.size()};
  array.data.assign(strings.size() * max_chars * 4, 0);
  for (size_t i = 0; i < decoded.size(); ++i) {
    // An empty string's vector may have no storage (data() null): memcpy from null is
    // undefined even for 0 bytes (UBSan), so it is skipped; its slot stays NULs.
    if (decoded[i].empty()) continue;
    std::memcpy(array.data.data() + i * max_chars * 4, decoded[i].data(), decoded[i].size() * 4);
  }
  return array;
}

NpyArray ParseNpy(const char* bytes, size_t size, const std::string& source) {
  THROW_IF(size < kNpyMagicSize + 4 || std::memcmp(bytes, kNpyMagic, kNpyMagicSize) != 0,
           source << ": not a .npy file (no \\x93NUMPY magic)");
  const int major = static_cast<unsigned char>(bytes[6]);
  size_t header_len = 0;
  size_t offset = 0;
  if (major == 1) {
    header_len = static_cast<unsigned char>(bytes[8]) |
                 (static_cast<size_t>(static_cast<unsigned char>(bytes[9])) << 8);
    offset = 10;
  } else if (major == 2 || major == 3) {
    THROW_IF(size < 12, source << ": truncated .npy header");
    for (int k = 0; k < 4; ++k) {
      header_len |= static_cast<size_t>(static_cast<unsigned char>(bytes[8 + k])) << (8 * k);
    }
    offset = 12;
  } else {
    HAIRMVS_THROW(source << ": unsupported .npy format version " << major);
  }
  THROW_IF(offset + header_len > size, source << ": truncated .npy header");
  const std::string header(bytes + offset, header_len);
  offset += header_len;

  NpyArray array;
  array.dtype = Unquote(HeaderValue(header, "descr", source), source);
  THROW_IF(!array.dtype.empty() && array.dtype[0] == '>',
           source << ": big-endian dtype " << array.dtype << " is not supported");
  if (!array.dtype.empty() && array.dtype[0] == '=') array.dtype[0] = '<';
  // Single-byte types are written "|u1"; accept "<u1" too (not "<U1": one 4-byte character).
  if (array.dtype.size() == 3 && array.dtype[2] == '1' && array.dtype[0] == '<' &&
      array.dtype[1] != 'U') {
    array.dtype[0] = '|';
  }
  const bool is_string = array.dtype.size() > 1 && array.dtype[1] == 'U';
  THROW_IF(!is_string && NumericItemSize(array.dtype) == 0,
           source << ": unsupported dtype " << array.dtype);
  // numpy writes at least <U1.
  THROW_IF(is_string && StringItemChars(array.dtype) == 0,
           source << ": unsupported dtype " << array.dtype << " (strings of 1 to "
                  << kMaxNpyStringChars << " characters)");
  const std::string fortran = HeaderValue(header, "fortran_order", source);
  THROW_IF(fortran != "False",
           source << ": Fortran-order arrays are not supported (fortran_order = " << fortran
                  << "); save with numpy.ascontiguousarray");
  std::string shape_text = HeaderValue(header, "shape", source);
  THROW_IF(shape_text.size() < 2 || shape_text.front() != '(' || shape_text.back() != ')',
           source << ": malformed shape " << shape_text);
  for (const std::string& item : SplitString(shape_text.substr(1, shape_text.size() - 2), ",")) {
    const std::string dim = StripWhitespace(item);
    if (dim.empty()) continue;
    // 18 digits fit in 64 bits (std::stoull would throw out_of_range without the file's name).
    THROW_IF(dim.find_first_not_of("0123456789") != std::string::npos || dim.size() > 18,
             source << ": malformed shape " << shape_text);
    array.shape.push_back(std::stoull(dim));
  }
  // The product is checked as it grows: a corrupt shape must not wrap around to a size that
  // the file happens to hold.
  size_t payload = array.ItemSize();
  for (size_t d : array.shape) {
    THROW_IF(d != 0 && payload > std::numeric_limits<size_t>::max() / d,
             source << ": shape " << shape_text << " is larger than any file");
    payload *= d;
  }
  THROW_IF(size - offset < payload, source << ": truncated .npy data: " << (size - offset)
                                           << " bytes, expected " << payload);
  THROW_IF(size - offset > payload, source << ": " << (size - offset - payload)
                                           << " trailing bytes after the .npy data");
  array.data.assign(bytes + offset, bytes + offset + payload);
  return array;
}

std::string FormatNpy(const NpyArray& array) {
  CHECK_EQ(array.data.size(), array.NumElements() * array.ItemSize());
  std::ostringstream dict;
  dict << "{'descr': '" << array.dtype << "', 'fortran_order': False, 'shape': (";
  for (size_t d : array.shape) dict << d << (array.shape.size() == 1 ? "," : ", ");
  std::string header = dict.str();
  if (array.shape.size() > 1) header.resize(header.size() - 2);
  header += "), }";
  // numpy pads the header with spaces and a final newline so the data is 64-byte aligned.
  size_t total = kNpyMagicSize + 4 + header.size() + 1;
  header.append((64 - total % 64) % 64, ' ');
  header.push_back('\n');
  CHECK_LT(header.size(), 65536u);
  std::string out(kNpyMagic, kNpyMagicSize);
  out.push_back('\x01');
  out.push_back('\x00');
  out.push_back(static_cast<char>(header.size() & 0xFF));
  out.push_back(static_cast<char>(header.size() >> 8));
  out += header;
  out.append(array.data.data(), array.data.size());
  return out;
}

NpyArray ReadNpy(const std::string& path) {
  RequireFile(path, ".npy file");
  std::ifstream in(path, std::ios::binary);
  THROW_IF(!in, "Cannot open " << path);
  std::ostringstream buffer;
  buffer << in.rdbuf();
  const std::string bytes = buffer.str();
  return ParseNpy(bytes.data(), bytes.size(), path);
}

std::map<std::string, NpyArray> ReadNpz(const std::string& path) {
  RequireFile(path, ".npz file");
  int error_code = 0;
  zip_t* archive = zip_open(path.c_str(), ZIP_RDONLY, &error_code);
  THROW_IF(archive == nullptr,
           path << ": not a readable .npz (zip) archive: " << ZipErrorString(error_code));
  std::unique_ptr<zip_t, int (*)(zip_t*)> guard(archive, zip_close);
  std::map<std::string, NpyArray> arrays;
  const zip_int64_t num_entries = zip_get_num_entries(archive, 0);
  for (zip_int64_t i = 0; i < num_entries; ++i) {
    zip_stat_t stat;
    zip_stat_init(&stat);
    THROW_IF(zip_stat_index(archive, i, 0, &stat) != 0,
             path << ": cannot read entry " << i << ": " << zip_strerror(archive));
    std::string name = stat.name;
    const std::string source = path + ":" + name;
    THROW_IF(name.size() < 4 || name.substr(name.size() - 4) != ".npy",
             source << ": .npz entry is not a .npy file");
    zip_file_t* file = zip_fopen_index(archive, i, 0);
    THROW_IF(file == nullptr, source << ": cannot open entry: " << zip_strerror(archive));
    std::unique_ptr<zip_file_t, int (*)(zip_file_t*)> file_guard(file, zip_fclose);
    // Read in chunks as the data comes, not into a buffer of the size the archive states: a
    // corrupt or hostile size field would otherwise allocate (and zero) gigabytes up front.
    std::vector<char> bytes;
    constexpr size_t kChunk = size_t{1} << 20;
    while (bytes.size() < stat.size) {
      const size_t old_size = bytes.size();
      bytes.resize(old_size + std::min<uint64_t>(kChunk, stat.size - old_size));
      const zip_int64_t n = zip_fread(file, bytes.data() + old_size, bytes.size() - old_size);
      THROW_IF(n < 0, source << ": corrupt or truncated entry: " << zip_file_strerror(file));
      bytes.resize(old_size + static_cast<size_t>(n));
      if (n == 0) break;
    }
    THROW_IF(bytes.size() != stat.size,
             source << ": truncated entry (" << bytes.size() << " of " << stat.size << " bytes)");
    // libzip checks the entry's CRC once a read reaches its end, not on the last byte asked for:
    // without this read, a corrupt deflate stream of the right length would be taken as data.
    char past_end = 0;
    const zip_int64_t at_end = zip_fread(file, &past_end, 1);
    THROW_IF(at_end != 0, source << ": corrupt entry: "
                                 << (at_end < 0 ? zip_file_strerror(file)
                                                : "longer than its stated size"));
    name.resize(name.size() - 4);
    arrays[name] = ParseNpy(bytes.data(), bytes.size(), source);
  }
  return arrays;
}

void WriteNpy(const std::string& path, const NpyArray& array) {
  const std::string bytes = FormatNpy(array);
  WriteFileAtomically(path, [&bytes](std::ostream& out) { out.write(bytes.data(), bytes.size()); });
}

void WriteNpz(const std::string& path, const std::map<std::string, NpyArray>& arrays) {
  // The formatted entries must outlive zip_close, which is when libzip compresses them.
  std::vector<std::string> buffers;
  buffers.reserve(arrays.size());
  for (const auto& [key, array] : arrays) buffers.push_back(FormatNpy(array));
  if (arrays.empty()) {
    // libzip writes no file for an empty archive; numpy writes the bare end record.
    const std::string empty_zip = std::string("PK\x05\x06", 4) + std::string(18, '\0');
    WriteFileAtomically(path, [&](std::ostream& out) { out << empty_zip; });
    return;
  }
  // The archive is made in memory and written like every other file: libzip writing a file
  // itself would make a temporary of its own, which an interrupt would leave behind.
  zip_error_t error;
  zip_error_init(&error);
  zip_source_t* memory = zip_source_buffer_create(nullptr, 0, 0, &error);
  THROW_IF(memory == nullptr, "Cannot create " << path << ": " << zip_error_strerror(&error));
  std::unique_ptr<zip_source_t, void (*)(zip_source_t*)> memory_guard(memory, zip_source_free);
  zip_t* archive = zip_open_from_source(memory, ZIP_TRUNCATE, &error);
  THROW_IF(archive == nullptr, "Cannot create " << path << ": " << zip_error_strerror(&error));
  zip_source_keep(memory);  // the archive's close must not free it: its bytes are read after
  size_t k = 0;
  for (const auto& [key, array] : arrays) {
    const std::string& bytes = buffers[k++];
    zip_source_t* source = zip_source_buffer(archive, bytes.data(), bytes.size(), 0);
    const zip_int64_t index =
        source == nullptr ? -1
                          : zip_file_add(archive, (key + ".npy").c_str(), source,
                                         ZIP_FL_ENC_UTF_8 | ZIP_FL_OVERWRITE);
    if (index < 0) {
      if (source != nullptr) zip_source_free(source);
      const std::string message = zip_strerror(archive);
      zip_discard(archive);
      HAIRMVS_THROW("Cannot add " << key << ".npy to " << path << ": " << message);
    }
    zip_set_file_compression(archive, index, ZIP_CM_DEFLATE, 6);
  }
  if (zip_close(archive) != 0) {
    const std::string message = zip_strerror(archive);
    zip_discard(archive);
    HAIRMVS_THROW("Cannot write " << path << ": " << message);
  }
  std::string zipped;
  bool read = zip_source_open(memory) == 0;
  if (read) {
    read = zip_source_seek(memory, 0, SEEK_END) == 0;
    const zip_int64_t size = read ? zip_source_tell(memory) : -1;
    read = size > 0 && zip_source_seek(memory, 0, SEEK_SET) == 0;
    if (read) {
      zipped.resize(static_cast<size_t>(size));
      read = zip_source_read(memory, zipped.data(), size) == size;
    }
    zip_source_close(memory);
  }
  THROW_IF(!read, "Cannot write " << path << ": " << zip_error_strerror(zip_source_error(memory)));
  WriteFileAtomically(path,
                      [&zipped](std::ostream& out) { out.write(zipped.data(), zipped.size()); });
}

const NpyArray& NpzEntry(const std::map<std::string, NpyArray>& arrays, const std::string& key,
                         const std::string& path) {
  const auto it = arrays.find(key);
  THROW_IF(it == arrays.end(), path << ": no array '" << key << "' in the archive");
  return it->second;
}

}  // namespace hairmvs
