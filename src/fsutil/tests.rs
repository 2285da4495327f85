use super::*;

#[test]
fn long_lines_are_discarded_in_bounded_memory() {
    let mut input: Vec<u8> = b"pause\r\n".to_vec();
    input.extend(std::iter::repeat_n(b'a', 1 << 20));
    input.extend(b"\nresume\nlast");
    let mut r = std::io::BufReader::with_capacity(64, &input[..]);
    let mut got = Vec::new();
    loop {
        match read_line_bounded(&mut r, 100).unwrap() {
            BoundedLine::End => break,
            l => got.push(l),
        }
    }
    assert_eq!(
        got,
        [
            BoundedLine::Line("pause".into()),
            BoundedLine::TooLong { bytes: 1 << 20 },
            BoundedLine::Line("resume".into()),
            BoundedLine::Line("last".into()),
        ]
    );
    // No newline at all.
    let endless = vec![b'a'; 10_000];
    let mut r = std::io::BufReader::with_capacity(16, &endless[..]);
    assert_eq!(
        read_line_bounded(&mut r, 100).unwrap(),
        BoundedLine::TooLong { bytes: 10_000 }
    );
    assert_eq!(read_line_bounded(&mut r, 100).unwrap(), BoundedLine::End);
}

#[test]
fn special_files_and_oversized_files_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    assert!(matches!(
        read_file(dir.path(), FileKind::Mesh),
        Err(ReadError::NotRegular("a folder"))
    ));
    #[cfg(unix)]
    {
        let e = read_file(Path::new("/dev/zero"), FileKind::Mesh).unwrap_err();
        assert_eq!(e, ReadError::NotRegular("a device"));
        let fifo = dir.path().join("fifo");
        let ok = std::process::Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .is_ok_and(|s| s.success());
        if ok {
            let e = read_file(&fifo, FileKind::Document).unwrap_err();
            assert_eq!(e, ReadError::NotRegular("a FIFO"));
        }
    }
    let big = dir.path().join("big.rhai");
    let f = std::fs::File::create(&big).unwrap();
    f.set_len(FileKind::Script.max_bytes() + 1).unwrap();
    let e = read_file(&big, FileKind::Script).unwrap_err();
    assert!(e.to_string().contains("4 MiB limit for a script"), "{e}");
    std::fs::write(&big, b"ok").unwrap();
    assert_eq!(read_text(&big, FileKind::Script).unwrap(), "ok");
    std::fs::write(&big, b"o\xffk").unwrap();
    assert_eq!(
        read_text(&big, FileKind::Script),
        Err(ReadError::NotText(1))
    );
}
