// A hiredis reply: owned by a unique_ptr that calls freeReplyObject, read through typed
// accessors that use the reply's length (strings may hold NUL bytes: unit results are binary).
#pragma once

#include <cstddef>
#include <memory>
#include <optional>
#include <string>
#include <string_view>

struct redisReply;

namespace rayfarm::farm {

// A non-owning view of a reply or of one of its elements.
class ReplyView {
 public:
  enum class Type { String, Array, Integer, Nil, SimpleString, ErrorReply };

  explicit ReplyView(const redisReply* r) : r_(r) {}
  Type type() const;
  bool is_nil() const { return type() == Type::Nil; }
  bool is_array() const { return type() == Type::Array; }
  // String, SimpleString and ErrorReply replies; empty otherwise.
  std::string_view str() const;
  // A bulk string, or nullopt for nil (and anything else).
  std::optional<std::string_view> string() const;
  long long integer() const;  // Integer replies; 0 otherwise
  // Array replies: the number of elements, and one of them (nil past the end).
  std::size_t size() const;
  ReplyView operator[](std::size_t i) const;

 private:
  const redisReply* r_;
};

class Reply : public ReplyView {
 public:
  struct Free {
    void operator()(redisReply* r) const;
  };
  explicit Reply(redisReply* r) : ReplyView(r), owner_(r) {}

 private:
  std::unique_ptr<redisReply, Free> owner_;
};

}  // namespace rayfarm::farm
