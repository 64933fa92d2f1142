#pragma once
// Internal to the message decoder (msg_decoder.cpp): bounds-checked reads of
// one serialized message, ROS 1 (packed) or CDR (aligned), either byte order.
#include <auvnav/import/record.h>

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <utility>

namespace auvnav::import::msg
{
constexpr bool kHostLittleEndian = __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__;

template <class T>
T byteSwapped(T v)
{
	unsigned char b[sizeof(T)];
	std::memcpy(b, &v, sizeof(T));
	for (std::size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(b[i], b[sizeof(T) - 1 - i]);
	std::memcpy(&v, b, sizeof(T));
	return v;
}

/** Bounds-checked reads of one message. kCdr: XCDR1 alignment relative to the
 *  byte after the encapsulation header, NUL-terminated strings, ROS 2 Time.
 *  Every read returns false, consuming nothing, when the bytes run out. */
template <bool kCdr>
class WireReader
{
 public:
	WireReader(const uint8_t* data, std::size_t size, std::size_t origin, bool swap)
	    : data_(data), size_(size), pos_(origin), origin_(origin), swap_(swap)
	{
	}

	std::size_t offset() const { return pos_; }
	std::size_t size() const { return size_; }
	std::size_t remaining() const { return size_ - pos_; }

	template <class T>
	bool get(T& v)
	{
		const std::size_t start = aligned(sizeof(T));
		if (start > size_ || size_ - start < sizeof(T)) return false;
		std::memcpy(&v, data_ + start, sizeof(T));
		if (swap_) v = byteSwapped(v);
		pos_ = start + sizeof(T);
		return true;
	}

	bool skip(std::size_t n)
	{
		if (remaining() < n) return false;
		pos_ += n;
		return true;
	}

	/** A string's bytes (without CDR's terminating NUL). */
	bool string(const char*& text, std::size_t& len)
	{
		const std::size_t start = pos_;
		uint32_t n = 0;
		if (!get(n) || remaining() < n)
		{
			pos_ = start;
			return false;
		}
		text = reinterpret_cast<const char*>(data_ + pos_);
		len = n;
		pos_ += n;
		if (kCdr && len > 0 && text[len - 1] == '\0') --len;
		return true;
	}

	/** ROS 1 time: uint32 sec, uint32 nsec; duration: int32, int32. ROS 2
	 *  Time and Duration: int32 sec, uint32 nanosec. */
	bool time(bool duration, TimeNs& out)
	{
		const std::size_t start = pos_;
		uint32_t sec = 0, nsec = 0;
		if (!get(sec) || !get(nsec))
		{
			pos_ = start;
			return false;
		}
		constexpr int64_t kNs = 1000000000;
		const bool signed_sec = kCdr || duration;
		const int64_t s =
		    signed_sec ? static_cast<int64_t>(static_cast<int32_t>(sec)) : static_cast<int64_t>(sec);
		const int64_t ns = (!kCdr && duration) ? static_cast<int64_t>(static_cast<int32_t>(nsec))
		                                       : static_cast<int64_t>(nsec);
		out = s * kNs + ns;
		return true;
	}

 private:
	std::size_t aligned(std::size_t n) const
	{
		if (!kCdr) return pos_;
		const std::size_t a = n > 8 ? 8 : n;
		const std::size_t rel = pos_ - origin_;
		return pos_ + (a - rel % a) % a;
	}

	const uint8_t* data_;
	std::size_t size_;
	std::size_t pos_;
	std::size_t origin_;
	bool swap_;
};

}  // namespace auvnav::import::msg
