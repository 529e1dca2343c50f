//! Physical line numbers for CSV records, whatever the line endings.
//!
//! Errors name the line of a bad cell, and users hand in CSV files written
//! by Python's `csv` module or spreadsheets, with CRLF endings, blank lines
//! or quoted cells spanning lines. The csv crate's own line count names a
//! CRLF file's records one line too low, so readers wrap their input in
//! [`LineCounting`], which notes where each line ends as bytes pass, and
//! look a record's byte offset up in it.

use std::cell::RefCell;
use std::collections::VecDeque;
use std::io::Read;

/// A reader that notes, as bytes pass, where each run of content after a
/// line ending (`\n`, `\r\n` or a lone `\r`) starts and on which line.
///
/// csv gives a record's position as the byte after the previous record's
/// terminator, which for CRLF is the `\n` and before blank lines is the
/// first of them; the record itself starts at the next content byte.
/// Records are looked up in order, so the starts before the last one
/// looked up are forgotten: memory stays within what csv has read ahead.
#[derive(Debug)]
pub struct LineCounting<R> {
    inner: R,
    offset: u64,
    line: usize,
    after_line_end: bool,
    after_cr: bool,
    in_quotes: bool,
    record_bytes: u64,
    starts: RefCell<VecDeque<(u64, usize)>>,
    /// The file's first two bytes, to tell UTF-16 text
    /// ([`crate::io::utf16_hint`]).
    start: Vec<u8>,
}

/// Longest record a CSV may hold (a row of `labels.csv` is about a hundred
/// bytes): a file without line ends (a sparse file claims terabytes of
/// zeros) is refused at this length instead of filling memory.
pub const MAX_RECORD_BYTES: u64 = 1 << 20;

impl<R: Read> LineCounting<R> {
    /// Wrap `inner`, counting from its first byte (line 1).
    pub fn new(inner: R) -> Self {
        Self {
            inner,
            offset: 0,
            line: 1,
            after_line_end: true,
            after_cr: false,
            in_quotes: false,
            record_bytes: 0,
            starts: RefCell::new(VecDeque::new()),
            start: Vec::new(),
        }
    }
}

impl<R> LineCounting<R> {
    /// The 1-based line of the first content byte at or after `byte`
    /// (`\r` and `\n` are not content); the last line when none follows.
    /// Lines before it are forgotten: ask in increasing order of `byte`.
    pub fn line_at(&self, byte: u64) -> usize {
        let mut starts = self.starts.borrow_mut();
        let i = starts.partition_point(|&(at, _)| at < byte);
        starts.drain(..i);
        starts.front().map_or(self.line, |&(_, line)| line)
    }

    /// The first bytes read (at most two).
    pub fn start(&self) -> &[u8] {
        &self.start
    }
}

impl<R: Read> Read for LineCounting<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.inner.read(buf)?;
        let more = (2 - self.start.len()).min(n);
        self.start.extend_from_slice(&buf[..more]);
        for (i, &b) in buf[..n].iter().enumerate() {
            // A record ends at a line end outside quotes.
            match b {
                b'"' => self.in_quotes = !self.in_quotes,
                b'\n' | b'\r' if !self.in_quotes => self.record_bytes = 0,
                _ => {}
            }
            self.record_bytes += 1;
            if self.record_bytes > MAX_RECORD_BYTES {
                return Err(std::io::Error::new(
                    std::io::ErrorKind::InvalidData,
                    format!("a record longer than {MAX_RECORD_BYTES} bytes (no line end)"),
                ));
            }
            // A line ends at `\n`, `\r\n` or a lone `\r` (as csv reads them).
            match b {
                b'\n' if self.after_cr => {}
                b'\n' | b'\r' => {
                    self.line += 1;
                    self.after_line_end = true;
                }
                _ if self.after_line_end => {
                    self.starts
                        .get_mut()
                        .push_back((self.offset + i as u64, self.line));
                    self.after_line_end = false;
                }
                _ => {}
            }
            self.after_cr = b == b'\r';
        }
        self.offset += n as u64;
        Ok(n)
    }
}

/// A csv reader whose records know their physical lines.
pub type CsvReader<R> = csv::Reader<LineCounting<R>>;

/// Build a csv reader from `builder` over `inner` with line counting.
pub fn reader<R: Read>(builder: &csv::ReaderBuilder, inner: R) -> CsvReader<R> {
    builder.from_reader(LineCounting::new(inner))
}

/// The header of a CSV file; else what is wrong with it, with how to save
/// the file when it is UTF-16 text.
pub fn headers<R: Read>(reader: &mut CsvReader<R>) -> Result<csv::StringRecord, String> {
    match reader.headers() {
        Ok(header) => Ok(header.clone()),
        Err(e) => Err(format!(
            "bad header: {e}{}",
            crate::io::utf16_hint(reader.get_ref().start())
        )),
    }
}

/// What to add to "no such column" when the header is one cell holding a
/// `;` or a tab: a spreadsheet saved the file with another separator
/// (Excel does so in locales that write decimal commas). Empty otherwise.
pub fn separator_hint<'a>(header: impl IntoIterator<Item = &'a str>) -> &'static str {
    let mut cells = header.into_iter();
    match (cells.next(), cells.next()) {
        (Some(only), None) if only.contains(';') => {
            " (the header is one cell holding ';': separate the columns with commas and \
             write decimal points, e.g. with pandas: \
             read_csv(f, sep=';', decimal=',').to_csv(f, index=False))"
        }
        (Some(only), None) if only.contains('\t') => {
            " (the header is one cell holding tabs: separate the columns with commas, e.g. \
             with pandas: read_csv(f, sep='\\t').to_csv(f, index=False))"
        }
        _ => "",
    }
}

/// Whether a header's first cell is the index pandas' `to_csv` writes
/// unless told `index=False`: a column without a name (`Unnamed: 0` once
/// read and saved again). Its readers drop it before the columns they
/// know.
pub fn is_pandas_index(first_cell: &str) -> bool {
    let name = first_cell.trim();
    name.is_empty() || name == "Unnamed: 0"
}

/// The records after the header, each with its physical line; a bad
/// record comes as its line and what is wrong with it ([`describe`]).
pub fn records<R: Read>(
    reader: &mut CsvReader<R>,
) -> impl Iterator<Item = Result<(usize, csv::StringRecord), (usize, String)>> + '_ {
    let mut it = reader.records();
    let mut count = 1;
    std::iter::from_fn(move || {
        let next = it.next()?;
        count += 1;
        let lines = it.reader().get_ref();
        let line = |p: Option<&csv::Position>| p.map_or(count, |p| lines.line_at(p.byte()));
        Some(match next {
            Ok(rec) => Ok((line(rec.position()), rec)),
            Err(e) => Err((line(e.position()), describe(&e))),
        })
    })
}

/// What is wrong with a record, without csv's own position (whose line
/// count is off for CRLF files): the caller names the line.
pub fn describe(e: &csv::Error) -> String {
    match e.kind() {
        csv::ErrorKind::UnequalLengths {
            expected_len, len, ..
        } => format!("{len} cells where the header has {expected_len}"),
        csv::ErrorKind::Utf8 { err, .. } => {
            format!("cell {} is not valid UTF-8", err.field() + 1)
        }
        csv::ErrorKind::Io(err) => format!("cannot read: {err}"),
        _ => e.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lines(text: &str) -> Vec<usize> {
        let mut r = reader(&csv::ReaderBuilder::new(), text.as_bytes());
        records(&mut r).map(|item| item.unwrap().0).collect()
    }

    #[test]
    fn records_name_their_physical_lines_with_any_line_endings() {
        assert_eq!(lines("a,b\n1,2\n3,4\n"), [2, 3]);
        assert_eq!(lines("a,b\r\n1,2\r\n3,4\r\n"), [2, 3]);
        assert_eq!(lines("a,b\r\n1,2\r\n\r\n3,4"), [2, 4]);
        assert_eq!(lines("a,b\n\"x\ny\",2\n3,4\n"), [2, 4]);
        assert_eq!(lines("a,b\n\n\n1,2\r\n\r\n\r\n3,4"), [4, 7]);
        assert_eq!(lines("a,b\r1,2\r\r3,4\r"), [2, 4]);
    }

    #[test]
    fn a_long_file_keeps_only_the_lines_csv_has_read_ahead() {
        let text: String = std::iter::once("a,b\r\n".to_string())
            .chain((0..100_000).map(|i| format!("{i},x\r\n")))
            .collect();
        let mut r = reader(&csv::ReaderBuilder::new(), text.as_bytes());
        let mut last = 1;
        for item in records(&mut r) {
            let (line, _) = item.unwrap();
            assert_eq!(line, last + 1);
            last = line;
        }
        assert_eq!(last, 100_001);
        // Every line looked up was forgotten as the next was asked for.
        assert!(r.get_ref().starts.borrow().len() <= 1);
    }

    #[test]
    fn a_record_without_end_is_refused_at_its_bound() {
        // Zeros without a line end, as a sparse file reads: an error once
        // the bound is passed, not a record that fills memory.
        let zeros = std::io::repeat(0).take(4 * MAX_RECORD_BYTES);
        let mut r = reader(&csv::ReaderBuilder::new(), zeros);
        let e = r.headers().unwrap_err();
        assert!(describe(&e).contains("a record longer than"), "{e}");
        // A long quoted cell spanning lines counts as one record; records
        // just under the bound pass.
        let cell = "x".repeat(MAX_RECORD_BYTES as usize / 2);
        let text = format!("a,b\n\"{cell}\n{cell}\",2\n");
        let mut r = reader(&csv::ReaderBuilder::new(), text.as_bytes());
        assert!(records(&mut r).next().unwrap().is_err());
        let text = format!("a,b\n{cell},2\n{cell},3\n");
        let mut r = reader(&csv::ReaderBuilder::new(), text.as_bytes());
        assert_eq!(records(&mut r).filter(Result::is_ok).count(), 2);
    }

    #[test]
    fn an_error_names_the_line_of_the_bad_record() {
        let text = "a,b\r\n1,2\r\n3,4,5\r\n";
        let mut r = reader(&csv::ReaderBuilder::new(), text.as_bytes());
        let items: Vec<_> = records(&mut r).collect();
        assert_eq!(items[0].as_ref().unwrap().0, 2);
        let (line, why) = items[1].as_ref().unwrap_err();
        assert_eq!((*line, why.as_str()), (3, "3 cells where the header has 2"));
    }

    #[test]
    fn a_header_split_by_semicolons_or_tabs_is_named() {
        for (text, hint) in [
            ("file;shape;x_mm\nframes/a.png;flat;1,5\n", "holding ';'"),
            ("file\tshape\n", "holding tabs"),
        ] {
            let mut r = reader(&csv::ReaderBuilder::new(), text.as_bytes());
            let h = r.headers().unwrap().clone();
            assert!(separator_hint(h.iter()).contains(hint), "{text:?}");
        }
        let mut r = reader(&csv::ReaderBuilder::new(), "file,shape\n".as_bytes());
        let h = r.headers().unwrap().clone();
        assert_eq!(separator_hint(h.iter()), "");
        assert_eq!(separator_hint(["file"]), "");
    }
}
