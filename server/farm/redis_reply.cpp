#include "redis_reply.h"

#include <hiredis.h>

namespace rayfarm::farm {

void Reply::Free::operator()(redisReply* r) const { freeReplyObject(r); }

ReplyView::Type ReplyView::type() const {
  if (!r_) return Type::Nil;
  switch (r_->type) {
    case REDIS_REPLY_STRING: return Type::String;
    case REDIS_REPLY_ARRAY: return Type::Array;
    case REDIS_REPLY_INTEGER: return Type::Integer;
    case REDIS_REPLY_STATUS: return Type::SimpleString;
    case REDIS_REPLY_ERROR: return Type::ErrorReply;
    default: return Type::Nil;
  }
}

std::string_view ReplyView::str() const {
  Type t = type();
  if (t != Type::String && t != Type::SimpleString && t != Type::ErrorReply) return {};
  return {r_->str, r_->len};
}

std::optional<std::string_view> ReplyView::string() const {
  if (type() != Type::String) return std::nullopt;
  return std::string_view(r_->str, r_->len);
}

long long ReplyView::integer() const { return type() == Type::Integer ? r_->integer : 0; }

std::size_t ReplyView::size() const { return type() == Type::Array ? r_->elements : 0; }

ReplyView ReplyView::operator[](std::size_t i) const {
  return ReplyView(i < size() ? r_->element[i] : nullptr);
}

}  // namespace rayfarm::farm
