// Little binary files of exact doubles (checkpoints, cached results): a magic number, then
// values as they lie in memory, vectors and strings with their length in front. The readers
// check every length against what is left, so a truncated or corrupt file is an InputError
// naming it, never a crash.
#pragma once

#include "core/error.h"

#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

namespace ssslab {

class BinaryWriter {
  public:
    /// Starts the content with the 8-byte magic number.
    explicit BinaryWriter(const char magic[8]) : out_(magic, 8) {}
    template <class T>
    void put(const T& v) {
        out_.append(reinterpret_cast<const char*>(&v), sizeof(T));
    }
    void put_vec(const std::vector<double>& v) {
        put<std::uint64_t>(v.size());
        out_.append(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(double));
    }
    void put_str(const std::string& s) {
        put<std::uint64_t>(s.size());
        out_ += s;
    }
    std::string& bytes() { return out_; }

  private:
    std::string out_;
};

class BinaryReader {
  public:
    /// Reads `data` (named `name` in errors) after checking its magic number; a wrong one is an
    /// InputError "not an ssslab <what>".
    BinaryReader(const std::string& data, const std::string& name, const char magic[8],
                 const char* what)
        : d_(data), name_(name) {
        if (d_.size() < 8 || std::memcmp(d_.data(), magic, 8) != 0)
            throw InputError({name_, 0, 0}, "", std::string("not an ssslab ") + what);
    }
    template <class T>
    T get() {
        need(sizeof(T));
        T v;
        std::memcpy(&v, d_.data() + pos_, sizeof(T));
        pos_ += sizeof(T);
        return v;
    }
    std::vector<double> get_vec() {
        const auto n = get<std::uint64_t>();
        need(n * sizeof(double));
        std::vector<double> v(n);
        std::memcpy(v.data(), d_.data() + pos_, n * sizeof(double));
        pos_ += n * sizeof(double);
        return v;
    }
    std::string get_str() {
        const auto n = get<std::uint64_t>();
        need(n);
        std::string s = d_.substr(pos_, n);
        pos_ += n;
        return s;
    }
    /// Throws unless `n` more bytes are left.
    void need(std::uint64_t n) const {
        if (n > d_.size() - pos_)
            throw InputError({name_, 0, 0}, "", "file is truncated or corrupt");
    }
    /// Throws unless everything was read.
    void expect_end() const {
        if (pos_ != d_.size())
            throw InputError({name_, 0, 0}, "", "trailing bytes: file is corrupt");
    }

  private:
    const std::string& d_;
    const std::string& name_;
    size_t pos_ = 8;
};

}  // namespace ssslab
