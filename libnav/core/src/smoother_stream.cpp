// Stretch file, forward recorder and backward pass (smoother_stream.h).
#include <auvnav/enum_names.h>
#include <auvnav/smoother_stream.h>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>

namespace auvnav
{
namespace
{
constexpr char kMagic[8] = {'A', 'U', 'V', 'N', 'V', 'R', 'T', 'S'};
constexpr std::uint32_t kVersion = 1;
constexpr int kMetaDoubles = 6;  // t, ticks, flags, repairs, limit hits, spare

std::size_t triangle(int n)
{
	return static_cast<std::size_t>(n) * (n + 1) / 2;
}

/** Doubles in one record: meta, attitude, euclidean part, P and ΣΔP as
 *  lower triangles, M and M_mean, Σ M dx. */
std::size_t recordDoubles(int n)
{
	return kMetaDoubles + 9 + n + 2 * triangle(n) + 2 * static_cast<std::size_t>(n) * n + n;
}

std::runtime_error ioError(const std::string& path, const std::string& what)
{
	return std::runtime_error(path + ": " + what +
	                          (errno ? std::string(" (") + std::strerror(errno) + ")" : ""));
}

void putLower(double*& p, const Covariance& A)
{
	for (int j = 0; j < A.cols(); ++j)
		for (int i = j; i < A.rows(); ++i) *p++ = 0.5 * (A(i, j) + A(j, i));
}
void getLower(const double*& p, Covariance& A, int n)
{
	A.resize(n, n);
	for (int j = 0; j < n; ++j)
		for (int i = j; i < n; ++i) A(i, j) = A(j, i) = *p++;
}
void putFull(double*& p, const Covariance& A)
{
	std::memcpy(p, A.data(), sizeof(double) * A.size());
	p += A.size();
}
void getFull(const double*& p, Covariance& A, int n)
{
	A.resize(n, n);
	std::memcpy(A.data(), p, sizeof(double) * A.size());
	p += A.size();
}

void writeAll(std::FILE* f, const void* data, std::size_t bytes, const std::string& path)
{
	if (bytes && std::fwrite(data, 1, bytes, f) != bytes) throw ioError(path, "write failed");
}
void writeString(std::FILE* f, const std::string& s, const std::string& path)
{
	const std::uint32_t len = static_cast<std::uint32_t>(s.size());
	writeAll(f, &len, sizeof len, path);
	writeAll(f, s.data(), s.size(), path);
}
void readAll(std::FILE* f, void* data, std::size_t bytes, const std::string& path)
{
	if (bytes && std::fread(data, 1, bytes, f) != bytes)
		throw ioError(path, "truncated or unreadable stretch file");
}
std::string readString(std::FILE* f, const std::string& path)
{
	std::uint32_t len = 0;
	readAll(f, &len, sizeof len, path);
	if (len > 4096)
		throw std::runtime_error(path + ": not a stretch file (a name of " + std::to_string(len) + " bytes)");
	std::string s(len, '\0');
	readAll(f, s.data(), len, path);
	return s;
}
}  // namespace

std::uint64_t stretchRecordBytes(int n)
{
	return sizeof(double) * recordDoubles(n);
}

StretchWriter::StretchWriter(const std::string& path, const StretchFileHeader& h) : path_(path), n_(h.n)
{
	if (h.n < idx::core_dim || h.n > idx::max_dim)
		throw std::invalid_argument(path + ": bad state dimension");
	f_ = io::openCFile(path, "wb", "cannot create the smoother's stretch file");
	writeHeader(h);  // a throw closes f_ (c_file.h)
}

void StretchWriter::writeHeader(const StretchFileHeader& h)
{
	writeAll(f_.get(), kMagic, sizeof kMagic, path_);
	const std::uint32_t v[2] = {kVersion, static_cast<std::uint32_t>(h.n)};
	writeAll(f_.get(), v, sizeof v, path_);
	writeAll(f_.get(), h.imu_position_b.data(), 3 * sizeof(double), path_);
	const std::uint32_t counts[2] = {static_cast<std::uint32_t>(h.tangent_names.size()),
	                                 static_cast<std::uint32_t>(h.stored_names.size())};
	writeAll(f_.get(), counts, sizeof counts, path_);
	for (const auto& s : h.tangent_names) writeString(f_.get(), s, path_);
	for (const auto& s : h.stored_names) writeString(f_.get(), s, path_);
	// Records start at a multiple of 8 bytes after the header's end.
	const long at = std::ftell(f_.get());
	const std::uint64_t data_offset = (static_cast<std::uint64_t>(at) + sizeof(std::uint64_t) + 7) / 8 * 8;
	writeAll(f_.get(), &data_offset, sizeof data_offset, path_);
	static const char zeros[8] = {};
	writeAll(f_.get(), zeros, data_offset - (at + sizeof data_offset), path_);
	buf_.resize(recordDoubles(n_));
	flush();
}

void StretchWriter::write(const StretchRecord& r)
{
	const RtsStretch& s = r.stretch;
	if (s.x_filtered.dim() != n_ || s.P_filtered.rows() != n_)
		throw std::invalid_argument(path_ + ": record of another dimension");
	double* p = buf_.data();
	*p++ = s.t_s;
	*p++ = static_cast<double>(s.ticks);
	*p++ = (s.broken ? 1 : 0) + (r.ends_segment ? 2 : 0);
	*p++ = r.repairs;
	*p++ = r.limit_hits;
	*p++ = 0;
	std::memcpy(p, s.x_filtered.R_nb.data(), 9 * sizeof(double));
	p += 9;
	const TangentVector e = s.x_filtered.euclidean();
	std::memcpy(p, e.data(), n_ * sizeof(double));
	p += n_;
	putLower(p, s.P_filtered);
	const bool has_stretch = !r.ends_segment && s.M.rows() == n_;
	if (has_stretch)
	{
		putLower(p, s.sum_dP);
		putFull(p, s.M);
		putFull(p, s.M_mean);
		std::memcpy(p, s.sum_dx.data(), n_ * sizeof(double));
		p += n_;
	}
	else
		std::fill(p, buf_.data() + buf_.size(), 0.0), p = buf_.data() + buf_.size();
	errno = 0;
	writeAll(f_.get(), buf_.data(), buf_.size() * sizeof(double), path_);
	++records_;
}

void StretchWriter::flush()
{
	errno = 0;
	if (std::fflush(f_.get()) != 0) throw ioError(path_, "write failed");
}

std::uint64_t StretchWriter::bytes() const
{
	return records_ * stretchRecordBytes(n_);
}

StretchReader::StretchReader(const std::string& path) : path_(path)
{
	f_ = io::openCFile(path, "rb", "cannot open the smoother's stretch file");
	readHeader();  // a refused file is closed by f_'s destructor (fuzz_stretch once found a handle left per
	               // refused file)
}

void StretchReader::readHeader()
{
	const std::string& path = path_;
	char magic[8];
	readAll(f_.get(), magic, sizeof magic, path_);
	if (std::memcmp(magic, kMagic, sizeof magic) != 0)
		throw std::runtime_error(path + ": not an auvnav stretch file");
	std::uint32_t v[2];
	readAll(f_.get(), v, sizeof v, path_);
	if (v[0] != kVersion)
		throw std::runtime_error(path + ": stretch file format " + std::to_string(v[0]) +
		                         ", this build reads " + std::to_string(kVersion));
	header_.n = static_cast<int>(v[1]);
	if (header_.n < idx::core_dim || header_.n > idx::max_dim)
		throw std::runtime_error(path + ": state dimension " + std::to_string(v[1]) + " out of range");
	readAll(f_.get(), header_.imu_position_b.data(), 3 * sizeof(double), path_);
	std::uint32_t counts[2];
	readAll(f_.get(), counts, sizeof counts, path_);
	if (counts[0] != v[1] || counts[1] != v[1])
		throw std::runtime_error(path + ": name lists do not match the dimension");
	for (std::uint32_t i = 0; i < counts[0]; ++i)
		header_.tangent_names.push_back(readString(f_.get(), path_));
	for (std::uint32_t i = 0; i < counts[1]; ++i) header_.stored_names.push_back(readString(f_.get(), path_));
	readAll(f_.get(), &data_offset_, sizeof data_offset_, path_);
	record_bytes_ = stretchRecordBytes(header_.n);
	if (fseeko(f_.get(), 0, SEEK_END) != 0) throw ioError(path, "cannot seek");
	const off_t end = ftello(f_.get());
	if (end < 0 || static_cast<std::uint64_t>(end) < data_offset_)
		throw std::runtime_error(path + ": truncated header");
	const std::uint64_t body = static_cast<std::uint64_t>(end) - data_offset_;
	records_ = static_cast<std::size_t>(body / record_bytes_);
	partial_tail_ = body % record_bytes_ != 0;
	buf_.resize(recordDoubles(header_.n));
}

StretchRecord StretchReader::read(std::size_t i)
{
	if (i >= records_)
		throw std::out_of_range(path_ + ": record " + std::to_string(i) + " of " + std::to_string(records_));
	errno = 0;
	if (fseeko(f_.get(), static_cast<off_t>(data_offset_ + i * record_bytes_), SEEK_SET) != 0)
		throw ioError(path_, "cannot seek");
	readAll(f_.get(), buf_.data(), buf_.size() * sizeof(double), path_);
	const int n = header_.n;
	// A damaged file is refused here, naming the record, never converted:
	// a double out of an integer's range is undefined behaviour to cast.
	auto refuse = [&](const std::string& what)
	{ throw std::runtime_error(path_ + ": record " + std::to_string(i) + ": " + what); };
	for (const double v : buf_)
		if (!std::isfinite(v)) refuse("a number that is not finite");
	const double* p = buf_.data();
	auto count = [&](double v, double max, const char* what)
	{
		if (!(v >= 0 && v <= max && v == std::floor(v))) refuse(std::string("bad ") + what);
		return v;
	};
	StretchRecord r;
	RtsStretch& s = r.stretch;
	s.t_s = *p++;
	s.ticks = static_cast<std::size_t>(count(*p++, 9007199254740992.0, "tick count"));
	const int flags = static_cast<int>(count(*p++, 3, "flags"));
	s.broken = flags & 1;
	r.ends_segment = flags & 2;
	r.repairs = static_cast<std::uint32_t>(count(*p++, 4294967295.0, "repair count"));
	r.limit_hits = static_cast<std::uint32_t>(count(*p++, 4294967295.0, "sigma-limit count"));
	++p;
	std::memcpy(s.x_filtered.R_nb.data(), p, 9 * sizeof(double));
	p += 9;
	TangentVector e(n);
	std::memcpy(e.data(), p, n * sizeof(double));
	p += n;
	s.x_filtered.extra.resize(n - idx::core_dim);
	s.x_filtered.setEuclidean(e);
	getLower(p, s.P_filtered, n);
	if (!r.ends_segment)
	{
		getLower(p, s.sum_dP, n);
		getFull(p, s.M, n);
		getFull(p, s.M_mean, n);
		s.sum_dx.resize(n);
		std::memcpy(s.sum_dx.data(), p, n * sizeof(double));
	}
	return r;
}

SmoothingRecorder::SmoothingRecorder(const std::string& path, const StretchFileHeader& header,
                                     double keep_every_s)
    : writer_(path, header), keep_every_s_(keep_every_s)
{
	if (!(keep_every_s > 0)) throw std::invalid_argument("smoother: keep_every_s must be positive");
}

void SmoothingRecorder::noteFilterCounters(const ManifoldUkf& ukf)
{
	s_.repairs += static_cast<std::uint32_t>(ukf.choleskyRepairs() - s_.repairs_seen);
	s_.limit_hits += static_cast<std::uint32_t>(ukf.sigmaLimitHits() - s_.limit_hits_seen);
	s_.repairs_seen = ukf.choleskyRepairs();
	s_.limit_hits_seen = ukf.sigmaLimitHits();
}

void SmoothingRecorder::emit(StretchRecord r)
{
	held_.push_back(std::move(r));
	++s_.emitted;
}

void SmoothingRecorder::predict(ManifoldUkf& ukf, const Eigen::Vector3d& omega_ib_b,
                                const Eigen::Vector3d& omega_ie_n, double dt_s, double t_s)
{
	noteFilterCounters(ukf);
	if (!s_.recorder.open())
	{
		s_.recorder.begin(ukf, t_s);
		s_.next_keep_s = t_s + keep_every_s_;
		s_.repairs = s_.limit_hits = 0;
	}
	else if (t_s >= s_.next_keep_s)
	{
		StretchRecord r;
		r.repairs = s_.repairs;
		r.limit_hits = s_.limit_hits;
		r.stretch = s_.recorder.close(ukf, t_s);
		if (r.repairs) r.stretch.broken = true;  // P was replaced inside: not a Bayesian step
		emit(std::move(r));
		s_.repairs = s_.limit_hits = 0;
		// The next kept tick on the grid, or one period on after a gap.
		s_.next_keep_s += keep_every_s_;
		if (s_.next_keep_s <= t_s) s_.next_keep_s = t_s + keep_every_s_;
	}
	s_.recorder.predict(ukf, omega_ib_b, omega_ie_n, dt_s);
}

void SmoothingRecorder::endSegment(const ManifoldUkf& ukf, double t_s)
{
	noteFilterCounters(ukf);
	if (!s_.recorder.open()) return;
	StretchRecord r;
	r.repairs = s_.repairs;
	r.limit_hits = s_.limit_hits;
	r.stretch = s_.recorder.close(ukf, t_s);
	if (r.repairs) r.stretch.broken = true;
	emit(std::move(r));
	// The estimate the segment ends on; the recorder starts again at the next prediction.
	StretchRecord end;
	end.ends_segment = true;
	end.stretch.t_s = t_s;
	end.stretch.x_filtered = ukf.state();
	end.stretch.P_filtered = ukf.covariance();
	emit(std::move(end));
	s_.recorder = RtsStretchRecorder{};
	s_.repairs = s_.limit_hits = 0;
	++segments_;
}

void SmoothingRecorder::finish(const ManifoldUkf& ukf, double t_s)
{
	endSegment(ukf, t_s);
	commit(std::numeric_limits<std::size_t>::max());
}

const SmoothingRecorder::Snapshot& SmoothingRecorder::snapshot(const ManifoldUkf& ukf)
{
	s_.recorder.checkRepairs(ukf);
	return s_;
}

void SmoothingRecorder::restore(const Snapshot& s, const ManifoldUkf& ukf)
{
	const std::size_t seen_repairs = s_.repairs_seen, seen_hits = s_.limit_hits_seen;
	s_ = s;
	s_.recorder.checkRepairs(ukf, true);
	// The filter's counters are not rewound: what the discarded pass counted is not this stretch's.
	s_.repairs_seen = seen_repairs;
	s_.limit_hits_seen = seen_hits;
	while (first_held_ + held_.size() > s_.emitted && !held_.empty()) held_.pop_back();
}

void SmoothingRecorder::commit(std::size_t emitted)
{
	bool wrote = false;
	while (!held_.empty() && first_held_ < emitted)
	{
		writer_.write(held_.front());
		held_.pop_front();
		++first_held_;
		wrote = true;
	}
	if (wrote) writer_.flush();
}

const char* smoothedKindName(SmoothedKind k)
{
	static constexpr const char* kNames[] = {"smoothed", "segment_end", "filtered_kept"};
	static_assert(namesEveryValue(kNames, SmoothedKind::Kept));
	return nameOf(kNames, k, "?");
}

BackwardPassSummary smoothStretchFile(
    const std::string& path,
    const std::function<void(double t_s, const NavState& x, const Covariance& P, SmoothedKind kind)>& out)
{
	StretchReader reader(path);
	BackwardPassSummary sum;
	sum.records = reader.records();
	sum.partial_tail = reader.partialTail();
	if (reader.records() == 0) return sum;
	// The last whole record ends what can be smoothed (the run's end, or
	// where an interrupted run's file stops).
	StretchRecord next = reader.read(reader.records() - 1);
	NavState x_next = next.stretch.x_filtered;
	Covariance P_next = next.stretch.P_filtered;
	out(next.stretch.t_s, x_next, P_next, SmoothedKind::SegmentEnd);
	++sum.segment_ends;
	NavState x;
	Covariance P;
	for (std::size_t i = reader.records() - 1; i-- > 0;)
	{
		StretchRecord r = reader.read(i);
		sum.repairs += r.repairs;
		sum.limit_hits += r.limit_hits;
		SmoothedKind kind;
		if (r.ends_segment)
		{
			x = r.stretch.x_filtered;
			P = r.stretch.P_filtered;
			kind = SmoothedKind::SegmentEnd;
			++sum.segment_ends;
		}
		else if (rtsStretchBackward(r.stretch, next.stretch.x_filtered, next.stretch.P_filtered, x_next,
		                            P_next, x, P))
		{
			kind = SmoothedKind::Smoothed;
			++sum.smoothed;
		}
		else
		{
			kind = SmoothedKind::Kept;
			++sum.kept;
		}
		out(r.stretch.t_s, x, P, kind);
		x_next = x;
		P_next = P;
		next = std::move(r);
	}
	return sum;
}

}  // namespace auvnav
