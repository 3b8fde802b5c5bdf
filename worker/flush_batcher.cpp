#include "worker/flush_batcher.h"

#include <algorithm>
#include <exception>
#include <stdexcept>

namespace farm {

FlushBatcher::FlushBatcher(double windowSeconds, Send send)
    : window_(std::chrono::duration_cast<Clock::duration>(
          std::chrono::duration<double>(std::max(0.0, windowSeconds)))),
      send_(std::move(send)) {}

std::string FlushBatcher::key(const std::string& jobId, uint32_t errorGroup) {
  return jobId + "/" + std::to_string(errorGroup);
}

void FlushBatcher::chainStarted(const std::string& key) {
  std::lock_guard<std::mutex> lock(mutex_);
  ++jobs_[key].running;
}

void FlushBatcher::chainEnded(const std::string& key) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    JobQueue& queue = jobs_[key];
    queue.running = std::max(0, queue.running - 1);
  }
  changed_.notify_all();  // the batch may be full now
}

FlushBatcher::Stats FlushBatcher::stats() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return stats_;
}

FlushReceipt FlushBatcher::upload(const LeasedChain& chain, ChainFlush&& flush) {
  Waiting self;
  self.item.chain = &chain;
  self.item.flush = std::move(flush);
  std::unique_lock<std::mutex> lock(mutex_);
  JobQueue& queue = jobs_[key(chain)];  // map nodes stay put: the reference outlives inserts
  const Clock::time_point arrived = Clock::now();
  // How long this flush may wait for its peers: the window, and no more than a share of the
  // time its chain took since its previous answer; for a chain's first flush, of the last
  // interval any chain of the job took (none yet: the window).
  if (auto last = queue.answered.find(self.item.flush.chainIndex); last != queue.answered.end()) {
    queue.interval = arrived - last->second;
  }
  Clock::duration wait = window_;
  if (queue.interval > Clock::duration::zero()) {
    wait = std::min(wait, std::chrono::duration_cast<Clock::duration>(queue.interval * kWaitShare));
  }
  if (queue.pending.empty()) {
    queue.due = arrived + wait;
  } else {
    queue.due = std::min(queue.due, arrived + wait);
  }
  queue.pending.push_back(&self);
  changed_.notify_all();
  while (!self.done) {
    const bool full = int(queue.pending.size()) >= std::max(1, queue.running);
    const bool due = Clock::now() >= queue.due;
    if (!queue.sending && !queue.pending.empty() && (full || due)) {
      // This thread sends the batch and answers everyone in it.
      std::vector<Waiting*> batch;
      batch.swap(queue.pending);
      queue.sending = true;
      ++stats_.batches;
      stats_.flushes += int64_t(batch.size());
      lock.unlock();
      std::vector<BatchItem*> items;
      for (Waiting* w : batch) items.push_back(&w->item);
      std::vector<BatchAnswer> answers;
      std::string failure;
      try {
        answers = send_(items);
        if (answers.size() != items.size()) failure = "the batch's answer does not match it";
      } catch (const std::exception& e) {
        failure = e.what();
      }
      lock.lock();
      queue.sending = false;
      std::vector<Waiting*> resend;
      for (size_t i = 0; i < batch.size(); ++i) {
        if (!failure.empty()) {
          batch[i]->answer.kind = BatchAnswer::Kind::kError;
          batch[i]->answer.error = failure;
        } else if (answers[i].kind == BatchAnswer::Kind::kResend) {
          resend.push_back(batch[i]);
          continue;
        } else {
          batch[i]->answer = std::move(answers[i]);
        }
        batch[i]->done = true;
      }
      if (!resend.empty()) {
        // Ahead of what arrived meanwhile, and due at once.
        resend.insert(resend.end(), queue.pending.begin(), queue.pending.end());
        queue.pending = std::move(resend);
        queue.due = Clock::now();
      }
      changed_.notify_all();
      continue;
    }
    if (queue.sending || queue.pending.empty()) {
      changed_.wait(lock);
    } else {
      changed_.wait_until(lock, queue.due);
    }
  }
  queue.answered[self.item.flush.chainIndex] = Clock::now();
  lock.unlock();
  if (self.answer.kind == BatchAnswer::Kind::kError) throw std::runtime_error(self.answer.error);
  return self.answer.receipt;
}

}  // namespace farm
