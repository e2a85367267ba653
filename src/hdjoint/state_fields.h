#pragma once
// A saved state as named fields. A class lists its state once, in
//   template <class Archive> bool fields(Archive& a) { return a("name", member, lo, hi) && ...; }
// and the same list writes the state (StateWriter: appends doubles) and
// reads it back (StateReader: takes doubles in the same order and checks
// each one -- finite, within [lo, hi], whole for counters, 0/1 for flags --
// naming the first field that fails). Nothing is ever read by position.
// Every reading checks every value the same way: the FMU's states and the
// core's load_state() (one validation; a test that plants a fault in a
// state must plant one that passes it).
#include <cmath>
#include <cstddef>
#include <sstream>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace hdjoint {

// Counters are stored as doubles: beyond 2^53 they are no longer exact.
constexpr double kMaxStoredCount = 9007199254740992.0;
constexpr double kUnbounded = 1e300;

class StateWriter {
public:
    explicit StateWriter(std::vector<double>* out) : out_(out) {}
    bool operator()(const char*, const double& v, double = -kUnbounded, double = kUnbounded) {
        out_->push_back(v);
        return true;
    }
    bool operator()(const char*, const long& v, double = 0.0, double = kMaxStoredCount) {
        out_->push_back(static_cast<double>(v));
        return true;
    }
    bool operator()(const char*, const bool& v) {
        out_->push_back(v ? 1.0 : 0.0);
        return true;
    }
    template <class Derived>
    bool operator()(const char*, const Eigen::PlainObjectBase<Derived>& m) {
        for (Eigen::Index i = 0; i < m.size(); ++i) out_->push_back(m.data()[i]);
        return true;
    }
    // A part that saves itself as a flat block: save(std::vector<double>*).
    template <class Part>
    bool part(const char*, const Part& p) {
        p.save(out_);
        return true;
    }
    bool refuse(const std::string&) { return false; }

private:
    std::vector<double>* out_;
};

class StateReader {
public:
    explicit StateReader(const std::vector<double>& in) : in_(in) {}

    bool operator()(const char* name, double& v, double lo = -kUnbounded, double hi = kUnbounded) {
        double x = 0.0;
        if (!take(name, &x, lo, hi)) return false;
        v = x;
        return true;
    }
    bool operator()(const char* name, long& v, double lo = 0.0, double hi = kMaxStoredCount) {
        double x = 0.0;
        if (!take(name, &x, lo, hi)) return false;
        if (x != std::floor(x)) return fail(name, x, "is not a whole number");
        v = static_cast<long>(x);  // in range: checked above
        return true;
    }
    bool operator()(const char* name, bool& v) {
        double x = 0.0;
        if (!take(name, &x, 0.0, 1.0)) return false;
        if (x != 0.0 && x != 1.0) return fail(name, x, "is not 0 or 1");
        v = x == 1.0;
        return true;
    }
    template <class Derived>
    bool operator()(const char* name, Eigen::PlainObjectBase<Derived>& m) {
        for (Eigen::Index i = 0; i < m.size(); ++i)
            if (!take(name, &m.data()[i], -kUnbounded, kUnbounded)) return false;
        return true;
    }
    // A part that loads itself: load(const std::vector<double>&, std::size_t* cursor) -> bool.
    // Its values are checked to be finite; its own load checks its layout.
    template <class Part>
    bool part(const char* name, Part& p) {
        const std::size_t begin = cursor_;
        if (!p.load(in_, &cursor_)) {
            problem_ = std::string("state part ") + name + " does not fit";
            return false;
        }
        for (std::size_t k = begin; k < cursor_; ++k)
            if (!std::isfinite(in_[k])) return fail(name, in_[k], "holds a value that is not finite");
        return true;
    }

    // Refuses what the fields read so far make invalid (say, a parameter set).
    bool refuse(const std::string& why) {
        problem_ = why;
        return false;
    }

    // True when every value was read; otherwise names what is left over.
    bool finished() {
        if (cursor_ == in_.size()) return true;
        problem_ = "state has " + std::to_string(in_.size() - cursor_) + " values more than this model saves";
        return false;
    }
    std::size_t cursor() const { return cursor_; }
    const std::string& problem() const { return problem_; }

private:
    bool take(const char* name, double* x, double lo, double hi) {
        if (cursor_ >= in_.size()) {
            problem_ = std::string("state ends before field ") + name;
            return false;
        }
        *x = in_[cursor_++];
        if (!std::isfinite(*x)) return fail(name, *x, "is not finite");
        if (*x < lo || *x > hi) {
            std::ostringstream range;
            range.precision(17);
            range << "is outside [" << lo << ", " << hi << "]";
            return fail(name, *x, range.str());
        }
        return true;
    }
    bool fail(const char* name, double x, const std::string& why) {
        std::ostringstream s;
        s.precision(17);
        s << "state field " << name << " = " << x << " " << why;
        problem_ = s.str();
        return false;
    }

    const std::vector<double>& in_;
    std::size_t cursor_ = 0;
    std::string problem_;
};

// An object's fields() as a flat vector, and back (all or nothing: a state
// that does not fit, or holds a value its field refuses, leaves the object as
// it was). The same reading as the FMU's: layout and every value checked.
template <class T>
std::vector<double> save_fields(const T& object) {
    std::vector<double> d;
    StateWriter w(&d);
    const_cast<T&>(object).fields(w);  // the writer only reads
    return d;
}
template <class T>
bool load_fields(T& object, const std::vector<double>& d, std::string* problem = nullptr) {
    T copy = object;
    StateReader r(d);
    if (!copy.fields(r) || !r.finished()) {
        if (problem) *problem = r.problem();
        return false;
    }
    object = std::move(copy);
    return true;
}

}  // namespace hdjoint
